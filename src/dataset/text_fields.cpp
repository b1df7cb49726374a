#include "text_fields.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <stdexcept>
#include <system_error>

namespace cge {
namespace dataset {
namespace detail {

std::vector<std::string_view> split_fields(std::string_view line) {
  constexpr std::string_view kBlanks = " \t\r";
  std::vector<std::string_view> fields;
  std::size_t pos = 0;
  while (true) {
    const std::size_t begin = line.find_first_not_of(kBlanks, pos);
    if (begin == std::string_view::npos) break;
    const std::size_t end = std::min(line.find_first_of(kBlanks, begin), line.size());
    fields.push_back(line.substr(begin, end - begin));
    pos = end;
  }
  return fields;
}

double parse_real(std::string_view field, const std::string& where, const char* what) {
  double value = 0;
  const char* first = field.data();
  const char* last = field.data() + field.size();
  if (first != last && *first == '+') ++first;  // from_chars refuses a leading '+'
  const auto r = std::from_chars(first, last, value);
  if (r.ec != std::errc() || r.ptr != last || !std::isfinite(value)) {
    throw std::invalid_argument(where + ": " + what + " '" + std::string(field) + "' is not a finite number");
  }
  return value;
}

std::ifstream open_text_file(const std::filesystem::path& file) {
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) {
    throw std::invalid_argument("'" + file.string() + "' does not exist");
  }
  if (!std::filesystem::is_regular_file(file, ec)) {
    throw std::invalid_argument("'" + file.string() + "' is not a regular file");
  }
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::invalid_argument("cannot open '" + file.string() + "' for reading");
  return in;
}

}  // namespace detail
}  // namespace dataset
}  // namespace cge
