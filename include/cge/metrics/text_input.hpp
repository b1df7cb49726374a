#pragma once
// Line-oriented text input shared by the metric readers (TUM trajectories, ground-truth loops,
// loops.csv): the error type, line reading, field splitting and locale-independent numbers.
// Every reader reports a malformed line as ParseError, "<source>:<line>: <reason>", with <source>
// the name the caller passes (a file name, or "<stdin>").

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <istream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "cge/core/parse_error.hpp"

namespace cge {
namespace metrics {

/// A malformed line (or a failed read) in text input: the toolkit's one ParseError
/// (cge/core/parse_error.hpp, a std::invalid_argument), "<source>:<line>: <reason>".
using ParseError = ::cge::ParseError;

namespace detail {

/// Reads lines one at a time, counting them, dropping a trailing '\r' and a UTF-8 byte order mark
/// on line 1. A stream failure other than the end of input throws ParseError.
class LineReader {
 public:
  LineReader(std::istream& in, std::string source) : in_(in), source_(std::move(source)) {}

  bool next(std::string& line) {
    if (!std::getline(in_, line)) {
      if (in_.bad()) throw ParseError(source_, line_number_ + 1, "read error");
      return false;
    }
    ++line_number_;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line_number_ == 1 && line.compare(0, 3, "\xEF\xBB\xBF") == 0) line.erase(0, 3);
    return true;
  }

  std::size_t line_number() const noexcept { return line_number_; }
  const std::string& source() const noexcept { return source_; }

  [[noreturn]] void fail(const std::string& reason) const { throw ParseError(source_, line_number_, reason); }

 private:
  std::istream& in_;
  std::string source_;
  std::size_t line_number_ = 0;
};

inline bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/// True for a line that is empty, all blanks, or whose first non-blank character is '#'.
inline bool is_blank_or_comment(std::string_view line) {
  for (const char c : line) {
    if (is_blank(c)) continue;
    return c == '#';
  }
  return true;
}

/// Splits a TUM-style line: any run of blanks and commas separates fields (the TUM tools replace
/// ',' and tabs by spaces and drop empty fields).
inline std::vector<std::string_view> split_blank_or_comma(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (is_blank(line[i]) || line[i] == ',')) ++i;
    const std::size_t start = i;
    while (i < line.size() && !(is_blank(line[i]) || line[i] == ',')) ++i;
    if (i > start) fields.push_back(line.substr(start, i - start));
  }
  return fields;
}

/// Splits a CSV line at every comma (no quoting); fields keep their blanks trimmed off both ends,
/// and an empty field stays an empty field.
inline std::vector<std::string_view> split_csv(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    std::string_view field =
        line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start);
    while (!field.empty() && is_blank(field.front())) field.remove_prefix(1);
    while (!field.empty() && is_blank(field.back())) field.remove_suffix(1);
    fields.push_back(field);
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return fields;
}

/// Parses a decimal number that must use the whole field (a leading '+' is allowed); false when it
/// does not. Locale-independent. "nan" and "inf" parse; callers check finiteness themselves.
inline bool parse_double(std::string_view field, double& out) {
  if (!field.empty() && field.front() == '+') {
    field.remove_prefix(1);
    if (!field.empty() && (field.front() == '+' || field.front() == '-')) return false;
  }
  if (field.empty()) return false;
  const char* last = field.data() + field.size();
  const std::from_chars_result r = std::from_chars(field.data(), last, out);
  return r.ec == std::errc() && r.ptr == last;
}

/// Parses a non-negative decimal integer (digits only) that fits a long long.
inline bool parse_count(std::string_view field, long long& out) {
  if (field.empty()) return false;
  for (const char c : field) {
    if (c < '0' || c > '9') return false;
  }
  const char* last = field.data() + field.size();
  const std::from_chars_result r = std::from_chars(field.data(), last, out);
  return r.ec == std::errc() && r.ptr == last;
}

inline std::string quoted(std::string_view field) { return "'" + std::string(field) + "'"; }

/// Opens a file for reading; throws std::invalid_argument naming it (and the system's reason)
/// when it cannot be opened.
inline std::ifstream open_input_file(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw std::invalid_argument("cannot read '" + path + "': it is a directory");
  errno = 0;
  std::ifstream file(path);
  const int err = errno;
  if (!file) {
    throw std::invalid_argument("cannot open '" + path + "'" +
                                (err != 0 ? std::string(": ") + std::strerror(err) : ""));
  }
  return file;
}

}  // namespace detail
}  // namespace metrics
}  // namespace cge
