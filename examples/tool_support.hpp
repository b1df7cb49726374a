#pragma once
// Small pieces every command-line tool of examples/ needs the same way: the exit codes, parsing
// and error reporting around a tool's body, a one-line progress bar on a terminal, and the final
// check that standard output really was written. Private to the tools (not installed, not part of
// the library).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <stdexcept>
#include <string>

#include <CLI/CLI.hpp>

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
inline CLI::Validator above_zero() { return sign_check(false); }

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

}  // namespace cge_tool
