#pragma once
// Private helpers of the dataset readers: whitespace-separated fields and strict number parsing
// with messages that name the place ("<file>:<line>").

#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

namespace cge {
namespace dataset {
namespace detail {

/// The blank-separated fields of a line (spaces, tabs; a trailing '\r' ignored).
std::vector<std::string_view> split_fields(std::string_view line);

/// The whole field as a finite double; throws std::invalid_argument "<where>: <what> '<field>' ...".
double parse_real(std::string_view field, const std::string& where, const char* what);

/// Opens a text file; throws std::invalid_argument naming it when it is missing, not a regular
/// file or unreadable.
std::ifstream open_text_file(const std::filesystem::path& file);

}  // namespace detail
}  // namespace dataset
}  // namespace cge
