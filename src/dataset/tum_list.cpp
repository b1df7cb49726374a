#include "cge/dataset/tum_list.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <istream>
#include <stdexcept>
#include <string_view>
#include <tuple>

#include "text_fields.hpp"

namespace cge {
namespace dataset {

std::vector<TumListEntry> parse_tum_list(std::istream& in, const std::string& source) {
  constexpr std::size_t kFields = 2;
  std::vector<TumListEntry> entries;
  std::string text;
  for (int line = 1; std::getline(in, text); ++line) {
    const std::vector<std::string_view> fields = detail::split_fields(text);
    if (fields.empty() || fields[0][0] == '#') continue;
    const std::string where = source + ":" + std::to_string(line);
    if (fields.size() != kFields) {
      throw std::invalid_argument(where + ": expected `timestamp path`, got " + std::to_string(fields.size()) +
                                  " fields");
    }
    TumListEntry e;
    e.timestamp_s = detail::parse_real(fields[0], where, "timestamp");
    e.token = std::string(fields[0]);
    e.path = std::string(fields[1]);
    e.line = line;
    if (!entries.empty() && !(e.timestamp_s > entries.back().timestamp_s)) {
      throw std::invalid_argument(where + ": timestamp " + e.token + " does not come after " + entries.back().token +
                                  " (line " + std::to_string(entries.back().line) + "); timestamps must increase");
    }
    entries.push_back(std::move(e));
  }
  if (in.bad()) throw std::invalid_argument(source + ": read error");
  return entries;
}

std::vector<TumListEntry> read_tum_list(const std::filesystem::path& file) {
  std::ifstream in = detail::open_text_file(file);
  return parse_tum_list(in, file.string());
}

namespace {

void require_increasing(const std::vector<double>& t, const char* which) {
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (!std::isfinite(t[i]) || (i > 0 && !(t[i] > t[i - 1]))) {
      throw std::invalid_argument(std::string("associate_timestamps: the ") + which +
                                  " list is not finite and strictly increasing at index " + std::to_string(i));
    }
  }
}

}  // namespace

std::vector<TimestampMatch> associate_timestamps(const std::vector<double>& first_s,
                                                 const std::vector<double>& second_s, double max_difference_s,
                                                 double offset_s) {
  if (!(std::isfinite(max_difference_s) && max_difference_s > 0)) {
    throw std::invalid_argument("associate_timestamps: the maximum difference must be finite and positive");
  }
  if (!std::isfinite(offset_s)) throw std::invalid_argument("associate_timestamps: the offset must be finite");
  require_increasing(first_s, "first");
  require_increasing(second_s, "second");

  // Candidates inside a window twice as wide as needed (so that rounding in the window bounds
  // cannot drop a pair), filtered by associate.py's own expression.
  struct Candidate {
    double difference_s;
    std::size_t first, second;
  };
  std::vector<Candidate> candidates;
  std::size_t start = 0;
  for (std::size_t i = 0; i < first_s.size(); ++i) {
    const double a = first_s[i];
    const double low = a - 2 * max_difference_s;
    const double high = a + 2 * max_difference_s;
    while (start < second_s.size() && second_s[start] + offset_s < low) ++start;
    for (std::size_t j = start; j < second_s.size() && second_s[j] + offset_s <= high; ++j) {
      const double d = std::abs(a - (second_s[j] + offset_s));
      if (d < max_difference_s) candidates.push_back({d, i, j});
    }
  }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& x, const Candidate& y) {
    return std::tie(x.difference_s, x.first, x.second) < std::tie(y.difference_s, y.first, y.second);
  });
  std::vector<char> first_used(first_s.size(), 0), second_used(second_s.size(), 0);
  std::vector<TimestampMatch> matches;
  for (const Candidate& c : candidates) {
    if (first_used[c.first] || second_used[c.second]) continue;
    first_used[c.first] = second_used[c.second] = 1;
    matches.push_back({c.first, c.second});
  }
  std::sort(matches.begin(), matches.end(),
            [](const TimestampMatch& x, const TimestampMatch& y) { return x.first < y.first; });
  return matches;
}

}  // namespace dataset
}  // namespace cge
