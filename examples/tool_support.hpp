#pragma once
// Small pieces every command-line tool of examples/ needs the same way: the exit codes, parsing
// and error reporting around a tool's body, a one-line progress bar on a terminal, and the final
// check that standard output really was written. Private to the tools (not installed, not part of
// the library).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include <unistd.h>

#include <CLI/CLI.hpp>

#include "cge/io/created_folders.hpp"

namespace cge_tool {

/// Exit codes of the tools: success; a failure while running (e.g. a file that cannot be
/// written); bad usage or input, found before anything is written.
constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;
constexpr int kExitUsage = 2;

/// Bad usage found after parsing (a missing input, a value out of range): exit code kExitUsage.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// A progress bar redrawn in place on standard error: "<program>: [=====>    ] done/total frames  t s".
/// The caller draws it only when standard error is a terminal.
class ProgressBar {
 public:
  explicit ProgressBar(const char* program, int width = 40) : program_(program), width_(width) {}

  void draw(int done, int total, double elapsed_s) {
    const int filled = static_cast<int>(static_cast<long long>(width_) * done / std::max(total, 1));
    std::string bar(static_cast<std::size_t>(width_), ' ');
    std::fill(bar.begin(), bar.begin() + filled, '=');
    if (filled < width_) bar[static_cast<std::size_t>(filled)] = '>';
    std::fprintf(stderr, "\r%s: [%s] %d/%d frames  %.1f s", program_, bar.c_str(), done, total, elapsed_s);
    line_open_ = done < total;
    if (!line_open_) std::fputc('\n', stderr);
    std::fflush(stderr);
  }

  /// Ends an unfinished bar's line, so that an error message starts on a line of its own.
  void end_line() {
    if (line_open_) std::fputc('\n', stderr);
    line_open_ = false;
  }

 private:
  const char* program_;
  int width_;               ///< characters between the brackets
  bool line_open_ = false;  ///< the bar is on the terminal without its newline yet
};

/// Flushes standard output (C and C++ streams) and reports whether everything reached it; when
/// not, prints "<program>: error: cannot write to standard output" on standard error.
inline bool standard_output_written(const char* program) {
  std::cout.flush();
  std::fflush(stdout);
  if (std::cout && !std::ferror(stdout)) return true;
  std::fprintf(stderr, "%s: error: cannot write to standard output\n", program);
  return false;
}

/// The shortest of "%.15g", "%.16g", "%.17g" that reads back as `value` ("-inf" for -infinity):
/// numbers the tools write for reading back (CSV columns, a recipe's flags).
inline std::string round_trip_number(double value) {
  char buf[64];
  for (const int digits : {15, 16, 17}) {
    std::snprintf(buf, sizeof buf, "%.*g", digits, value);
    if (std::strtod(buf, nullptr) == value) break;
  }
  return buf;
}

/// Option checks with short messages ("must be >= 0, got -2"); CLI11's own NonNegativeNumber and
/// PositiveNumber print the range with the largest double written out in full. A value that is not
/// a number passes through to CLI11's conversion, which reports it.
inline CLI::Validator sign_check(bool zero_allowed) {
  const std::string rule = zero_allowed ? ">= 0" : "> 0";
  return CLI::Validator(
      [zero_allowed, rule](const std::string& text) {
        char* end = nullptr;
        const double value = std::strtod(text.c_str(), &end);
        if (end == text.c_str() || *end != '\0' || value > 0 || (zero_allowed && value == 0)) return std::string();
        return "must be " + rule + ", got " + text;
      },
      rule);
}
inline CLI::Validator at_least_zero() { return sign_check(true); }

/// Seeds are unsigned 64-bit; CLI11 would wrap "-1" to 2^64 - 1 without a word.
inline CLI::Validator seed_check() {
  return CLI::Validator(
      [](const std::string& text) {
        const std::size_t first = text.find_first_not_of(" \t");
        if (first != std::string::npos && text[first] == '-') return "must be 0 .. 2^64 - 1, got " + text;
        return std::string();
      },
      "0 .. 2^64 - 1");
}
inline CLI::Validator above_zero() { return sign_check(false); }

/// A bad count or size, checked before any work: "<option> must be at most <limit> (<why>), got <value>".
inline void require_at_most(const char* option, double value, double limit, const char* why) {
  if (value <= limit) return;
  char text[160];
  std::snprintf(text, sizeof text, "%s must be at most %.15g (%s), got %.15g", option, limit, why, value);
  throw UsageError(text);
}

/// Missing folders on the way to an output: created, and removed again when the run fails.
using CreatedFolders = cge::io::CreatedFolders;

/// Checks an output file's name before the work: a folder there is refused as a folder, an
/// existing file unless `force` (UsageError naming `what`, e.g. "--out").
inline void check_output_file(const std::string& path, const std::string& what, bool force) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (path.empty()) throw UsageError(what + " must name a file");
  const fs::file_status st = fs::status(path, ec);
  if (fs::is_directory(st)) throw UsageError(what + ": '" + path + "' is a directory, not a file");
  if (fs::exists(st) && !force) throw UsageError(what + ": '" + path + "' exists (pass --force to overwrite it)");
}

/// A temporary name beside `path` with the same extension (image writers choose the format by
/// it): "<folder>/.<name>.partial.<pid><extension>".
inline std::filesystem::path partial_name(const std::filesystem::path& path) {
  const std::filesystem::path name = path.filename();
  return path.parent_path() /
         ("." + name.stem().string() + ".partial." + std::to_string(::getpid()) + name.extension().string());
}

/// Replaces `path` with what `write_to(temporary path)` writes, all or nothing: the temporary is
/// renamed over `path` only when `write_to` returned true, and removed otherwise. A failure
/// throws std::runtime_error (exit code 1), and `path` is as it was.
template <typename WriteTo>
void replace_file(const std::filesystem::path& path, WriteTo&& write_to) {
  const std::filesystem::path temporary = partial_name(path);
  std::error_code ec;
  bool ok = false;
  try {
    ok = write_to(temporary);
  } catch (...) {
    std::filesystem::remove(temporary, ec);
    throw;
  }
  if (ok) std::filesystem::rename(temporary, path, ec);
  if (!ok || ec) {
    std::filesystem::remove(temporary, ec);
    throw std::runtime_error("cannot write '" + path.string() + "'");
  }
}

/// replace_file for a text or binary stream: `writer(std::ostream&)`.
template <typename Writer>
void replace_file_with_stream(const std::filesystem::path& path, Writer&& writer) {
  replace_file(path, [&writer](const std::filesystem::path& temporary) {
    std::ofstream file(temporary, std::ios::binary | std::ios::trunc);
    if (!file) return false;
    writer(file);
    file.flush();
    return static_cast<bool>(file);
  });
}

/// Parses the command line as every tool does. Returns -1 when the tool should go on; otherwise
/// the exit code: 0 after --help or --version (CLI11 printed them), kExitUsage after a parse error
/// (unknown flag, bad value), with the message and a hint on standard error.
inline int parse_command_line(CLI::App& app, int argc, char** argv, const char* program) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app.exit(e);
    std::fprintf(stderr, "%s: error: %s\nRun with --help for more information.\n", program, e.what());
    return kExitUsage;
  }
  return -1;
}

/// Runs a tool's body (returning its exit code) and turns what it throws into "<program>: error:
/// <message>" on standard error and an exit code: UsageError and std::invalid_argument (bad input,
/// whose message names the item) kExitUsage, any other std::exception kExitFailure. `progress`
/// (may be null) has its unfinished line ended first, so the message starts on a line of its own.
template <class Body>
int run_reporting_errors(const char* program, ProgressBar* progress, Body&& body) {
  const auto report = [&](const std::exception& e, int exit_code) {
    if (progress != nullptr) progress->end_line();
    std::fprintf(stderr, "%s: error: %s\n", program, e.what());
    return exit_code;
  };
  try {
    return body();
  } catch (const UsageError& e) {
    return report(e, kExitUsage);
  } catch (const std::invalid_argument& e) {
    return report(e, kExitUsage);
  } catch (const std::exception& e) {
    return report(e, kExitFailure);
  }
}

/// Moves the tree `staging` into `out`: folders merge, files replace same-named files, anything
/// else in `out` stays. Every destination is checked before the first move, so one that is blocked
/// (a folder where a file goes, or the reverse) moves nothing: UsageError naming it. `staging` is
/// removed afterwards.
inline void move_staged_tree(const std::filesystem::path& staging, const std::filesystem::path& out) {
  namespace fs = std::filesystem;
  struct Entry {
    fs::path relative;  // to staging
    bool folder = false;
  };
  std::vector<Entry> entries;
  for (const fs::directory_entry& e : fs::recursive_directory_iterator(staging)) {
    entries.push_back({e.path().lexically_relative(staging), e.is_directory()});
  }
  // Element-wise path order: a folder before its contents.
  std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) { return a.relative < b.relative; });
  std::error_code ec;
  for (const Entry& e : entries) {
    const fs::file_status destination = fs::status(out / e.relative, ec);
    if (e.folder && fs::exists(destination) && !fs::is_directory(destination)) {
      throw UsageError("--out: '" + (out / e.relative).string() + "' is a file where a folder goes; nothing was written");
    }
    if (!e.folder && fs::is_directory(destination)) {
      throw UsageError("--out: '" + (out / e.relative).string() + "' is a folder where a file goes; nothing was written");
    }
  }
  for (const Entry& e : entries) {
    if (e.folder) {
      fs::create_directory(out / e.relative);  // no-op when it is there
    } else {
      fs::rename(staging / e.relative, out / e.relative);
    }
  }
  fs::remove_all(staging);
}

}  // namespace cge_tool
