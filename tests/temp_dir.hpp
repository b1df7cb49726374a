#pragma once
// A uniquely named temporary folder that the test creates and removes again (only that folder).

#include <chrono>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <system_error>

namespace cge_test {

class TempDir {
 public:
  explicit TempDir(const std::string& prefix) {
    namespace fs = std::filesystem;
    const auto base = fs::temp_directory_path();
    const auto stamp = std::chrono::steady_clock::now().time_since_epoch().count();
    for (int attempt = 0; attempt < 1000; ++attempt) {
      const fs::path candidate = base / (prefix + "_" + std::to_string(stamp) + "_" + std::to_string(attempt));
      std::error_code ec;
      if (fs::create_directory(candidate, ec)) {  // false when it exists already: someone else's
        path_ = candidate;
        return;
      }
    }
    throw std::runtime_error("TempDir: cannot create a unique folder under " + base.string());
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

}  // namespace cge_test
