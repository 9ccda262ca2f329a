// A command's output is never one of its inputs, nor inside an input folder.
#include "core/base/output_path.h"

#include <gtest/gtest.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <fstream>

#include "core/base/error.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;

std::string errorOf(const fs::path& output, std::initializer_list<CommandInput> inputs) {
  try {
    refuseOutputOverInputs("--out", output, inputs);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(OutputPath, AnOutputOverOrInsideAnInputIsRefused) {
  const fs::path dir =
      fs::temp_directory_path() / ("lumistage_output_path_" + std::to_string(::getpid()));
  fs::create_directories(dir / "session" / "cam01");
  std::ofstream(dir / "points.txt") << "x\n";
  const fs::path session = dir / "session", points = dir / "points.txt";
  // The same file, however it is spelt.
  std::string e = errorOf(dir / "." / "points.txt", {{"--points", points}});
  EXPECT_NE(e.find("it is --points " + points.string() + ", which the command reads"),
            std::string::npos)
      << e;
  // Inside a session folder (the file there or not yet), or the folder itself.
  e = errorOf(session / "session.yaml", {{"--points", points}, {"--session", session}});
  EXPECT_NE(e.find("inside --session " + session.string()), std::string::npos) << e;
  EXPECT_NE(errorOf(session / "cam01" / "new.png", {{"--session", dir / "session" / ""}}),
            "no error");
  EXPECT_NE(errorOf(session, {{"--session", session}}), "no error");
  // Beside them, or with the inputs left out: fine.
  EXPECT_EQ(errorOf(dir / "session2" / "x.json", {{"--session", session}}), "no error");
  EXPECT_EQ(errorOf(dir / "rig.yaml", {{"--points", points}, {"--session", ""}}), "no error");
  EXPECT_EQ(errorOf("", {{"--session", session}}), "no error");
  // A file input is no folder: an output "inside" it is not refused here (its open fails).
  EXPECT_EQ(errorOf(points / "x", {{"--points", points}}), "no error");
  // A folder to write into: checked before the work.
  EXPECT_NO_THROW(requireOutputFolder("--json", dir / "r.json"));
  EXPECT_NO_THROW(requireOutputFolder("--json", ""));
  try {
    requireOutputFolder("--json", dir / "nodir" / "r.json");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no folder " + (dir / "nodir").string()),
              std::string::npos)
        << e.what();
  }
  fs::remove_all(dir);
}

// The disk a takes folder is on, before the folder is made: its parent's, named after this
// machine, and another filesystem is another disk.
TEST(DiskSpace, AFolderNotMadeYetIsOnItsParentsDisk) {
  const fs::path dir = fs::temp_directory_path() / ("lumistage_disk_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const DiskSpace here = diskSpaceAt(dir), later = diskSpaceAt(dir / "takes" / "take-001");
  struct statvfs disk {};
  ASSERT_EQ(::statvfs(dir.c_str(), &disk), 0);
  const double free = double(disk.f_bavail) * double(disk.f_frsize);
  ASSERT_GT(free, 0);
  EXPECT_NEAR(double(here.free_bytes), free, 0.01 * free);
  EXPECT_NEAR(double(later.free_bytes), free, 0.01 * free);
  EXPECT_EQ(later.disk, here.disk);
  char host[256] = {};
  ASSERT_EQ(::gethostname(host, sizeof(host) - 1), 0);
  EXPECT_EQ(here.disk.rfind(std::string(host) + ":", 0), 0u) << here.disk;
  const DiskSpace proc = diskSpaceAt("/proc");
  EXPECT_FALSE(proc.disk.empty());
  EXPECT_NE(proc.disk, here.disk);
  fs::remove_all(dir);
}

TEST(DiskSpace, BytesInWordsForATechnician) {
  EXPECT_EQ(bytesInWords(812'400'000), "812 MB");
  EXPECT_EQ(bytesInWords(41'340'000'000), "41.3 GB");
  EXPECT_EQ(bytesInWords(1'204'000'000'000), "1.20 TB");
  EXPECT_EQ(bytesInWords(52'000), "52 kB");
}

}  // namespace
}  // namespace lumistage
