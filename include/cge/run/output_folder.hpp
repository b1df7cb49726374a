#pragma once
// OutputFolder: a tool's output folder filled all or nothing. Files are written into a hidden
// staging folder inside the output folder (".<tool>.partial.<pid>") and renamed into place only by
// commit(), after every destination was checked, so a failed run leaves the folder as it was; so
// does SIGTERM or SIGINT, whose handler removes the staging folder. Staging folders of processes no
// longer alive are leftovers of a killed run: they do not make the folder "not empty" and are
// removed. Missing folders on the way are created and removed again when the run fails
// (cge/io/created_folders.hpp). A non-empty folder is refused unless `force`; with `force` only the
// tool's own files (`names`) are replaced, nothing else is touched.
//
// Bad usage (a file where the folder goes, a non-empty folder without force, a folder where one
// of `names` goes) throws std::invalid_argument; a failure to write or move std::runtime_error.
// One OutputFolder at a time per process: the signal handler knows only the latest.
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "cge/io/created_folders.hpp"

namespace cge {
namespace run {

/// Whether `entry` is a staging folder ".<tool>.partial.<pid>" whose process is gone.
bool is_stale_staging(const std::filesystem::path& entry, const std::string& tool);

class OutputFolder {
 public:
  /// `tool` names the staging folder and the messages; `names` are every file the tool may write
  /// (at most kMaxNames), each checked before the run.
  OutputFolder(const std::filesystem::path& out, bool force, const std::string& tool,
               std::vector<std::string> names);
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;
  ~OutputFolder();

  static constexpr std::size_t kMaxNames = 16;

  /// Writes `name` (one of the names) into the staging folder through `writer(std::ostream&)`.
  template <typename Writer>
  void write(const std::string& name, Writer&& writer) {
    const std::filesystem::path path = stage(name);
    std::ofstream file(path, std::ios::binary);
    if (!file) throw std::runtime_error("cannot write " + path.string());
    writer(file);
    file.flush();
    if (!file) throw std::runtime_error("cannot write " + path.string());
  }

  /// A path in the staging folder for a writer that takes a file name; moved into the output
  /// folder on commit() like the others.
  std::filesystem::path stage(const std::string& name);

  /// Moves the staged files into the output folder; every destination is checked first (it may
  /// have changed during the run), so that the renames do not stop half-way over a user's folder.
  void commit();

  const std::filesystem::path& staging_folder() const { return staging_; }

 private:
  void check_destination(const std::string& name) const;
  void arm_signal_cleanup();

  io::CreatedFolders folders_;  // first member: destroyed last, after the staging folder
  std::filesystem::path out_, staging_;
  std::string tool_;
  std::vector<std::string> names_;   ///< every name the tool may write
  std::vector<std::string> staged_;  ///< the names written so far, in order
  bool created_out_ = false;
  bool committed_ = false;
};

}  // namespace run
}  // namespace cge
