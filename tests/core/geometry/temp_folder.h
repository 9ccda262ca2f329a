#pragma once

// A folder of files for the rig importers' tests, removed at the end of the test.

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace lumistage::testing {

class TempFolder {
 public:
  TempFolder() {
    path_ = std::filesystem::temp_directory_path() /
            ("lumistage_import_" + std::to_string(::getpid()) + "_" + std::to_string(counter_++));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempFolder() { std::filesystem::remove_all(path_); }
  const std::filesystem::path& path() const { return path_; }
  void write(const std::string& name, const std::string& text) const {
    std::ofstream(path_ / name) << text;
  }

 private:
  static inline int counter_ = 0;
  std::filesystem::path path_;
};

}  // namespace lumistage::testing
