#pragma once
// StderrCapture: holds what libraries write to the process's standard error (file descriptor 2)
// while it lives, e.g. libpng's "libpng error: Read Error" while OpenCV decodes a broken PNG, so
// that a tool's own message, which names the file, comes first; the caller may append the captured
// text to that message. POSIX only (dup, dup2, tmpfile). Not thread-safe: it swaps the
// descriptor of the whole process, so it belongs around short calls on the one thread that
// writes to standard error at the time.

#include <cstdio>
#include <string>

#include <unistd.h>

namespace cge {
namespace io {

class StderrCapture {
 public:
  StderrCapture() {
    std::fflush(stderr);
    file_ = std::tmpfile();
    if (file_ == nullptr) return;
    saved_ = ::dup(2);
    if (saved_ < 0 || ::dup2(::fileno(file_), 2) < 0) {
      if (saved_ >= 0) ::close(saved_);
      saved_ = -1;
    }
  }
  StderrCapture(const StderrCapture&) = delete;
  StderrCapture& operator=(const StderrCapture&) = delete;
  ~StderrCapture() {
    restore();
    if (file_ != nullptr) std::fclose(file_);
  }

  /// Ends the capture (standard error is the original again) and returns what was written,
  /// without a final newline.
  std::string finish() {
    restore();
    std::string text;
    if (file_ == nullptr) return text;
    std::rewind(file_);
    char buffer[512];
    std::size_t n = 0;
    while ((n = std::fread(buffer, 1, sizeof buffer, file_)) > 0 && text.size() < 4096) text.append(buffer, n);
    while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
    return text;
  }

 private:
  void restore() {
    if (saved_ < 0) return;
    std::fflush(stderr);
    ::dup2(saved_, 2);
    ::close(saved_);
    saved_ = -1;
  }

  std::FILE* file_ = nullptr;
  int saved_ = -1;
};

}  // namespace io
}  // namespace cge
