#pragma once
// The text lists of the TUM RGB-D benchmark and their association by timestamp.
//
// List format (rgb.txt, depth.txt): one `timestamp path` pair per line, separated by spaces or
// tabs; lines whose first non-blank character is '#' and blank lines are ignored; a trailing '\r'
// is ignored. Timestamps are seconds (any finite decimal number) and must increase strictly from
// line to line. Paths are relative to the list's folder (absolute paths are taken as they are).
//
// Association (TUM's associate.py): every pair (a, b) of a first and a second timestamp with
// |a - (b + offset)| < max_difference is a candidate; candidates are taken in increasing order of
// that difference (ties: smaller a, then smaller b) and a candidate is kept when neither of its
// timestamps is used yet. The result is sorted by the first timestamp.

#include <cstddef>
#include <filesystem>
#include <iosfwd>
#include <string>
#include <vector>

namespace cge {
namespace dataset {

/// One data line of a TUM list.
struct TumListEntry {
  double timestamp_s = 0;  ///< seconds, as written
  std::string token;       ///< the timestamp as written (the image stem in TUM: "1341846313.592026")
  std::string path;        ///< second field, as written
  int line = 0;            ///< 1-based line in the file, for messages
};

/// Parses a TUM list from `in`; `source` names it in messages. Throws std::invalid_argument
/// "<source>:<line>: ..." for a line that is not exactly `timestamp path`, a timestamp that does not
/// parse or is not finite, or a timestamp not greater than the previous line's.
std::vector<TumListEntry> parse_tum_list(std::istream& in, const std::string& source);

/// The same for a file; throws std::invalid_argument naming the file when it is missing or unreadable.
std::vector<TumListEntry> read_tum_list(const std::filesystem::path& file);

/// One associated pair: indices into the first and the second timestamp list.
struct TimestampMatch {
  std::size_t first = 0;
  std::size_t second = 0;
  friend bool operator==(const TimestampMatch& a, const TimestampMatch& b) {
    return a.first == b.first && a.second == b.second;
  }
};

/// Associates two timestamp lists by the rule of associate.py (above); both lists must be sorted
/// strictly increasing (what parse_tum_list guarantees). offset_s is added to the second list's
/// timestamps. Returns the matches sorted by `first`. Throws std::invalid_argument when a list is
/// not strictly increasing or max_difference_s is not finite and positive, or offset_s not finite.
std::vector<TimestampMatch> associate_timestamps(const std::vector<double>& first_s,
                                                 const std::vector<double>& second_s, double max_difference_s,
                                                 double offset_s = 0.0);

}  // namespace dataset
}  // namespace cge
