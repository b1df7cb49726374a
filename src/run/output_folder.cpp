#include "cge/run/output_folder.hpp"

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstring>

#include <signal.h>
#include <sys/types.h>
#include <unistd.h>

namespace cge {
namespace run {
namespace {

namespace fs = std::filesystem;

/// What the SIGTERM / SIGINT handler removes: the staging folder's possible files, the folder,
/// and the output folder when this run created it (rmdir: only when empty). Plain C strings,
/// written before the handler is installed, so that the handler only calls unlink, rmdir, signal
/// and raise (async-signal-safe).
struct SignalCleanup {
  static constexpr std::size_t kPathBytes = 4096;
  char staged[OutputFolder::kMaxNames][kPathBytes] = {};
  int staged_count = 0;
  char staging[kPathBytes] = {};
  char created_out[kPathBytes] = {};
};
SignalCleanup signal_cleanup;
volatile std::sig_atomic_t cleanup_armed = 0;

extern "C" void remove_staging_and_die(int signal_number) {
  if (cleanup_armed != 0) {
    for (int i = 0; i < signal_cleanup.staged_count; ++i) ::unlink(signal_cleanup.staged[i]);
    ::rmdir(signal_cleanup.staging);
    if (signal_cleanup.created_out[0] != '\0') ::rmdir(signal_cleanup.created_out);
  }
  std::signal(signal_number, SIG_DFL);
  std::raise(signal_number);
}

bool copy_path(char* to, const fs::path& from) {
  const std::string text = from.string();
  if (text.size() + 1 > SignalCleanup::kPathBytes) return false;
  std::memcpy(to, text.c_str(), text.size() + 1);
  return true;
}

std::string staging_prefix(const std::string& tool) { return "." + tool + ".partial."; }

}  // namespace

bool is_stale_staging(const fs::path& entry, const std::string& tool) {
  const std::string name = entry.filename().string();
  const std::string prefix = staging_prefix(tool);
  if (name.compare(0, prefix.size(), prefix) != 0 || name.size() == prefix.size()) return false;
  const std::string digits = name.substr(prefix.size());
  if (digits.find_first_not_of("0123456789") != std::string::npos || digits.size() > 9) return false;
  const long pid = std::stol(digits);
  if (pid == static_cast<long>(::getpid())) return false;
  return ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH;
}

OutputFolder::OutputFolder(const fs::path& out, bool force, const std::string& tool, std::vector<std::string> names)
    : out_(out), tool_(tool), names_(std::move(names)) {
  if (names_.size() > kMaxNames) throw std::logic_error("OutputFolder: more than kMaxNames file names");
  std::error_code ec;
  std::vector<fs::path> stale;
  if (fs::exists(out_, ec)) {
    if (!fs::is_directory(out_, ec)) throw std::invalid_argument("'" + out_.string() + "' exists and is not a folder");
    bool other_entries = false;
    for (const auto& entry : fs::directory_iterator(out_, ec)) {
      if (is_stale_staging(entry.path(), tool_)) {
        stale.push_back(entry.path());
      } else {
        other_entries = true;
      }
    }
    if (other_entries && !force) {
      throw std::invalid_argument("'" + out_.string() + "' exists and is not empty (use --force to replace " + tool_ +
                                  "'s files in it)");
    }
    // Replacing must not fail half-way: every destination must be a file or free.
    for (const std::string& name : names_) check_destination(name);
  } else {
    folders_.create(out_, "--out");
    created_out_ = true;
  }
  for (const fs::path& p : stale) fs::remove_all(p, ec);  // a killed run's files, never the user's
  staging_ = out_ / (staging_prefix(tool_) + std::to_string(::getpid()));
  fs::create_directory(staging_, ec);
  if (ec) throw std::runtime_error("cannot create '" + staging_.string() + "': " + ec.message());
  arm_signal_cleanup();
}

OutputFolder::~OutputFolder() {
  cleanup_armed = 0;
  if (committed_) return;
  std::error_code ec;
  fs::remove_all(staging_, ec);  // our own folder, holding only our files
  // folders_ (destroyed after this body) removes the folders this run created, when empty.
}

fs::path OutputFolder::stage(const std::string& name) {
  if (std::find(names_.begin(), names_.end(), name) == names_.end()) {
    throw std::logic_error("OutputFolder: '" + name + "' is not one of the tool's file names");
  }
  staged_.push_back(name);
  return staging_ / name;
}

void OutputFolder::commit() {
  for (const std::string& name : staged_) check_destination(name);
  for (const std::string& name : staged_) {
    std::error_code ec;
    fs::rename(staging_ / name, out_ / name, ec);
    if (ec) throw std::runtime_error("cannot move " + name + " into '" + out_.string() + "': " + ec.message());
  }
  cleanup_armed = 0;
  std::error_code ec;
  fs::remove(staging_, ec);
  committed_ = true;
  folders_.keep();
}

void OutputFolder::check_destination(const std::string& name) const {
  std::error_code ec;
  const fs::file_status st = fs::symlink_status(out_ / name, ec);
  if (fs::exists(st) && !fs::is_regular_file(st)) {
    throw std::invalid_argument("'" + (out_ / name).string() + "' exists and is not a file: " + tool_ +
                                " cannot replace it");
  }
}

void OutputFolder::arm_signal_cleanup() {
  SignalCleanup& c = signal_cleanup;
  bool fits = copy_path(c.staging, staging_);
  c.staged_count = 0;
  for (const std::string& name : names_) fits = fits && copy_path(c.staged[c.staged_count++], staging_ / name);
  c.created_out[0] = '\0';
  if (created_out_) fits = fits && copy_path(c.created_out, out_);
  if (!fits) return;  // a path longer than the buffers: no cleanup on signals
  cleanup_armed = 1;
  struct sigaction action {};
  action.sa_handler = remove_staging_and_die;
  sigemptyset(&action.sa_mask);
  ::sigaction(SIGTERM, &action, nullptr);
  ::sigaction(SIGINT, &action, nullptr);
}

}  // namespace run
}  // namespace cge
