#pragma once
// The one error type of every text reader in the toolkit (graph text, TUM trajectories, loop
// files, ...): a malformed line is invalid input, so it is a std::invalid_argument, and it keeps
// where the problem is so a tool can point at it. what() is "<source>:<line>: <reason>".
#include <cstddef>
#include <stdexcept>
#include <string>
#include <utility>

namespace cge {

class ParseError : public std::invalid_argument {
 public:
  ParseError(std::string source, std::size_t line, std::string reason)
      : std::invalid_argument(source + ":" + std::to_string(line) + ": " + reason),
        source_(std::move(source)),
        line_(line),
        reason_(std::move(reason)) {}

  /// The name the input was read under: a file name or "<stdin>".
  const std::string& source() const noexcept { return source_; }
  /// 1-based line number of the offending line.
  std::size_t line() const noexcept { return line_; }
  /// The problem alone, without "<source>:<line>: ".
  const std::string& reason() const noexcept { return reason_; }

 private:
  std::string source_;
  std::size_t line_;
  std::string reason_;
};

}  // namespace cge
