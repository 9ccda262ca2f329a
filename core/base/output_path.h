#pragma once

#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <string>
#include <string_view>

namespace lumistage {

// One of a command's inputs: the option that names it and the file or folder it reads.
struct CommandInput {
  std::string_view option;
  std::filesystem::path path;
};

// Throws Error when a command's output (`option`, `output`) is one of its inputs, or lies inside an
// input folder (a recorded session): "--json /s/session.yaml: inside --session /s, which it reads;
// write it elsewhere". Commands wrote over their own inputs without a word (eval's report over the
// session's session.yaml, a rig over the wand points it was solved from). Inputs or an output left
// empty are skipped; paths are compared once made absolute and free of . and .. (and of symbolic
// links, where they exist).
void refuseOutputOverInputs(std::string_view option, const std::filesystem::path& output,
                            std::initializer_list<CommandInput> inputs);

// Throws Error when the folder `output` would be written into does not exist ("--json nodir/r.json:
// no folder nodir to write it into"): checked before a command's work, not after a minute's run.
// An empty output is skipped.
void requireOutputFolder(std::string_view option, const std::filesystem::path& output);

// The disk that holds `path` (its nearest folder that exists: a takes folder not made yet is on its
// parent's disk): the space free to this user, in bytes, and a name that is the same for every
// path on that disk of this machine ("<host>:<filesystem id>"). -1 and empty when none can be
// asked.
struct DiskSpace {
  int64_t free_bytes = -1;
  std::string disk;
};
DiskSpace diskSpaceAt(const std::filesystem::path& path);

// Bytes in words for a technician: "812 MB", "41.3 GB", "1.20 TB".
std::string bytesInWords(int64_t bytes);

// The file's extension in lower case (".MP4" -> ".mp4"), which chooses its format; empty for none.
std::string lowercaseExtension(const std::filesystem::path& file);

}  // namespace lumistage
