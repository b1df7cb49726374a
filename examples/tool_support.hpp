#pragma once
// Small pieces every command-line tool of examples/ needs the same way: a one-line progress bar
// on a terminal, and the final check that standard output really was written. Private to the
// tools (not installed, not part of the library).
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <string>

namespace cge_tool {

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

}  // namespace cge_tool
