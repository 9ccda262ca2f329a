#pragma once

// A folder of files for the rig importers' tests: testing::testFolder()'s (the test's own, kept
// for a look when a test failed), one more for each made in the same test.

#include <filesystem>
#include <fstream>
#include <string>

#include "tests/test_util.h"

namespace lumistage::testing {

class TempFolder {
 public:
  TempFolder() : path_(testFolder("import_" + std::to_string(counter_++))) {}
  const std::filesystem::path& path() const { return path_; }
  void write(const std::string& name, const std::string& text) const {
    std::ofstream(path_ / name) << text;
  }

 private:
  static inline int counter_ = 0;
  std::filesystem::path path_;
};

}  // namespace lumistage::testing
