#pragma once
// The one rule of the tools for output locations (docs/CLI.md, "Output files and folders"): missing
// folders on the way to an output are created, as `mkdir -p` does, and removed again (those still
// empty) when the run fails before its outputs are in place; a part of the path that exists and is
// not a folder is bad input (std::invalid_argument naming the option).
#include <filesystem>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

namespace cge {
namespace io {

class CreatedFolders {
 public:
  CreatedFolders() = default;
  CreatedFolders(const CreatedFolders&) = delete;
  CreatedFolders& operator=(const CreatedFolders&) = delete;
  ~CreatedFolders() {
    for (auto it = created_.rbegin(); it != created_.rend(); ++it) {
      std::error_code ec;
      if (std::filesystem::is_empty(*it, ec) && !ec) std::filesystem::remove(*it, ec);
    }
  }

  /// Creates `folder` and its missing parents; `what` names the option in messages.
  void create(const std::filesystem::path& folder, const std::string& what) {
    namespace fs = std::filesystem;
    if (folder.empty()) return;
    std::vector<fs::path> missing;
    std::error_code ec;
    for (fs::path p = folder; !p.empty(); p = p.parent_path()) {
      const fs::file_status st = fs::status(p, ec);
      if (fs::is_directory(st)) break;
      if (fs::exists(st)) throw std::invalid_argument(what + ": '" + p.string() + "' exists and is not a folder");
      missing.push_back(p);
      if (p == p.parent_path()) break;
    }
    for (auto it = missing.rbegin(); it != missing.rend(); ++it) {
      if (!fs::create_directory(*it, ec) && ec) {
        throw std::runtime_error(what + ": cannot create the folder '" + it->string() + "': " + ec.message());
      }
      created_.push_back(*it);
    }
  }
  /// Creates the folder that `file` goes into.
  void create_parent_of(const std::filesystem::path& file, const std::string& what) {
    create(file.parent_path(), what);
  }
  /// The outputs are in place: the folders stay.
  void keep() { created_.clear(); }

 private:
  std::vector<std::filesystem::path> created_;
};

}  // namespace io
}  // namespace cge
