#include "core/base/atomic_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "core/base/error.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;

TEST(AtomicFile, WritesReplacesAndLeavesNoTemporaryBehind) {
  const fs::path folder =
      fs::temp_directory_path() / ("lumistage_atomic_" + std::to_string(::getpid()));
  fs::create_directories(folder);
  const fs::path file = folder / "a.txt";
  writeFileAtomically(file, "first");
  writeFileAtomically(file, "second, longer");
  EXPECT_EQ(readFile(file), "second, longer");
  EXPECT_EQ(std::distance(fs::directory_iterator(folder), fs::directory_iterator()), 1);
  fs::remove_all(folder);
}

TEST(AtomicFile, FailureNamesTheFileAndKeepsTheOldOne) {
  try {
    writeFileAtomically("/nonexistent-folder/rig.yaml", "x");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-folder/rig.yaml"), std::string::npos);
  }
  const fs::path folder =
      fs::temp_directory_path() / ("lumistage_atomic_dir_" + std::to_string(::getpid()));
  fs::create_directories(folder / "target");  // a folder where the file should go: rename fails
  EXPECT_THROW(writeFileAtomically(folder / "target", "x"), Error);
  EXPECT_TRUE(fs::is_directory(folder / "target"));
  EXPECT_EQ(std::distance(fs::directory_iterator(folder), fs::directory_iterator()), 1);
  fs::remove_all(folder);
}

TEST(AtomicFile, ReadingAFolderOrMissingFileIsAnError) {
  EXPECT_THROW(readFile(fs::temp_directory_path()), Error);
  EXPECT_THROW(readFile("/nonexistent/file"), Error);
}

}  // namespace
}  // namespace lumistage
