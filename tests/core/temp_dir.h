#pragma once
// Scratch folders for the tests under the system's temporary folder, one per name and test process. They
// are removed when the process ends with every test passed and kept after a failure, to look at (ctest
// runs each test in a process of its own). Before, every run of the suite left ~1 GB of them in /tmp.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <mutex>
#include <set>
#include <string>
#include <system_error>

namespace u3d::testing {

namespace detail {

class TempDirs {
 public:
  ~TempDirs() {
    // gtest's UnitTest is never destroyed, so it can still be asked here, at the process's end.
    if (!::testing::UnitTest::GetInstance()->Passed()) return;
    std::error_code ignored;
    for (const auto& dir : dirs_) std::filesystem::remove_all(dir, ignored);
  }
  void add(const std::filesystem::path& dir) {
    std::lock_guard<std::mutex> lock(mutex_);
    dirs_.insert(dir);
  }

 private:
  std::mutex mutex_;
  std::set<std::filesystem::path> dirs_;
};

inline TempDirs& temp_dirs() {
  static TempDirs dirs;
  return dirs;
}

}  // namespace detail

// A fresh empty folder `<temp>/u3d_test_<name>_<pid>`, apart from other test processes' folders.
inline std::filesystem::path fresh_temp_dir(const std::string& name) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("u3d_test_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  detail::temp_dirs().add(dir);
  return dir;
}

}  // namespace u3d::testing
