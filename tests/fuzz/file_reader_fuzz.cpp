// libFuzzer targets over the readers of files a user is handed (issue 54): BVH motion, rig and
// session YAML, wand points, and the Qualisys XML, TOML, OpenCV FileStorage and EasyMocap
// calibration imports. Each reader takes a path, so every input is written to a file first. Any
// input must give a result or an Error (std::exception) naming what is wrong, never a crash, a
// hang, unbounded memory or a read out of bounds (AddressSanitizer); the OpenCV readers' errors
// must moreover be our Error naming the file (no cv::Exception let through). One source, one
// binary a reader: LUMISTAGE_FUZZ_READER picks which.
// tests/CMakeLists.txt builds each with clang against the project's core library (the reader's
// own sources instrumented, the rest as built), and ctest fuzzes each for a few seconds
// (file_reader_fuzz_<reader>, by run_reader_fuzz.sh). Run at length by hand, e.g.
//   build/tests/file_reader_fuzz_toml -max_total_time=600 build/tests/fuzz/toml/corpus
// Found so far: the TOML import read past toml11's buffer (fixed in toml_rig_import.cpp); OpenCV
// 4.6's FileStorage crashed on a NUL byte, looped forever on YAML past a first document, allocated
// a matrix's declared size unchecked and threw std::length_error (file_storage_nesting.cpp,
// file_storage_matrix.cpp).
// With LUMISTAGE_FUZZ_SEED_DIR set, the target first copies its reader's valid examples there
// (LUMISTAGE_FUZZ_SEEDS, ':'-separated files), so the fuzzer starts from inputs that parse. A
// session names its rig file: LUMISTAGE_FUZZ_RIG, copied beside every session as rig.yaml.
// EasyMocap's calibration is two files: an input is intri.yml up to a line kExtriMarker, and
// extri.yml after it (empty where there is none).
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "core/base/error.h"
#include "core/body/bvh.h"
#include "core/body/human_skeleton.h"
#include "core/calib/wand_session.h"
#include "core/capture/session_reader.h"
#include "core/geometry/rig_file.h"
#include "core/geometry/rig_import.h"

namespace {

namespace fs = std::filesystem;
using namespace lumistage;

// The folder of the file every input is written to; removed when the fuzzer exits.
const fs::path& inputFolder() {
  static const fs::path dir =
      fs::temp_directory_path() / ("lumistage_fuzz_" + std::to_string(::getpid()));
  return dir;
}

// The file every input is written to, named as its reader expects.
const fs::path& inputFile() {
  static const fs::path file = [] {
    const char* extension = LUMISTAGE_FUZZ_EXTENSION;
    const fs::path& dir = inputFolder();
    fs::create_directories(dir);
    std::atexit([] {
      std::error_code ignored;
      fs::remove_all(inputFolder(), ignored);
    });
    if (const char* rig = std::getenv("LUMISTAGE_FUZZ_RIG"); rig != nullptr)
      fs::copy_file(rig, dir / "rig.yaml", fs::copy_options::overwrite_existing);
    // A session is a folder whose session.yaml names the rest; EasyMocap's, one with intri.yml.
    return dir / (LUMISTAGE_FUZZ_READER == 6   ? std::string("session.yaml")
                  : LUMISTAGE_FUZZ_READER == 8 ? std::string("intri.yml")
                                               : std::string("input") + extension);
  }();
  return file;
}

// The line that ends intri.yml and starts extri.yml in an EasyMocap input.
constexpr std::string_view kExtriMarker = "\n# ---- extri.yml ----\n";

void write(const fs::path& file, std::string_view data) {
  std::ofstream(file, std::ios::binary | std::ios::trunc)
      .write(data.data(), std::streamsize(data.size()));
}

// The input written where its reader looks for it.
void writeInput(std::string_view data) {
  const fs::path& file = inputFile();
  if (LUMISTAGE_FUZZ_READER != 8) return write(file, data);
  const size_t marker = data.find(kExtriMarker);
  write(file, data.substr(0, marker));
  write(file.parent_path() / "extri.yml", marker == std::string_view::npos
                                              ? std::string_view()
                                              : data.substr(marker + kExtriMarker.size()));
}

void read(const fs::path& file) {
#if LUMISTAGE_FUZZ_READER == 1
  static const Skeleton target = makeHumanSkeleton();
  (void)loadBvh(file, target);
#elif LUMISTAGE_FUZZ_READER == 2
  (void)loadRig(file);
#elif LUMISTAGE_FUZZ_READER == 3
  (void)loadWandSession(file);
#elif LUMISTAGE_FUZZ_READER == 4
  (void)importQualisysRig(file, {});
#elif LUMISTAGE_FUZZ_READER == 5
  (void)importTomlRig(file, {});
#elif LUMISTAGE_FUZZ_READER == 6
  // A session's session.yaml, in a session folder of its own (its rig: a file beside it).
  (void)SessionReader(file.parent_path());
#elif LUMISTAGE_FUZZ_READER == 7
  (void)importOpenCvRig(file, {});
#elif LUMISTAGE_FUZZ_READER == 8
  // An image size given, as --image-size does, so that files without W_ and H_ get further.
  RigImportOptions options;
  options.width = 1920;
  options.height = 1080;
  (void)importEasyMocapRig(file.parent_path(), options);
#else
#error \
    "LUMISTAGE_FUZZ_READER: 1 BVH, 2 rig, 3 wand, 4 Qualisys, 5 TOML, 6 session, 7 OpenCV, \
8 EasyMocap"
#endif
}

// The OpenCV readers: a refusal is our Error naming the file (the folder, for EasyMocap's two),
// never an OpenCV or other library exception let through. Anything else aborts, which libFuzzer
// reports with the input that did it.
void checkRefusal([[maybe_unused]] const std::exception& e) {
#if LUMISTAGE_FUZZ_READER == 7 || LUMISTAGE_FUZZ_READER == 8
  const std::string named = inputFile().parent_path().string();
  if (dynamic_cast<const Error*>(&e) == nullptr ||
      std::string_view(e.what()).find(named) == std::string_view::npos) {
    std::fprintf(stderr, "refused without naming %s as an Error: %s\n", named.c_str(),
                 quotedInput(e.what()).c_str());
    std::abort();
  }
#endif
}

void copySeeds() {
  const char* dir = std::getenv("LUMISTAGE_FUZZ_SEED_DIR");
  const char* seeds = std::getenv("LUMISTAGE_FUZZ_SEEDS");
  if (dir == nullptr || seeds == nullptr) return;
  std::string list = seeds;
  for (size_t start = 0, n = 0; start <= list.size(); ++n) {
    const size_t end = std::min(list.find(':', start), list.size());
    const fs::path seed = list.substr(start, end - start);
    std::error_code ignored;
    if (!seed.empty())
      fs::copy_file(seed, fs::path(dir) / ("seed" + std::to_string(n)),
                    fs::copy_options::overwrite_existing, ignored);
    start = end + 1;
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  copySeeds();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  writeInput(std::string_view(reinterpret_cast<const char*>(data), size));
  try {
    read(inputFile());
  } catch (const std::exception& e) {
    // Refused with a reason: what a reader should do with a bad file.
    checkRefusal(e);
  }
  return 0;
}
