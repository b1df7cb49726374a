#pragma once
// Reader of ground-truth loops in the synthetic sequences' loops.txt (docs/SIMULATION.md):
// '#' comment lines and blank lines are skipped; every other line is
// "query_timestamp match_timestamp query_index match_index" (blanks, tabs or commas between the
// fields), one line per frame pair that revisits a place, with finite timestamps, non-negative
// whole indices, match_index < query_index and match_timestamp < query_timestamp. A malformed line
// throws ParseError ("<source>:<line>: <reason>"). A file with only comments has no loops.

#include <cmath>
#include <cstddef>
#include <istream>
#include <string>
#include <string_view>
#include <vector>

#include "cge/metrics/text_input.hpp"

namespace cge {
namespace metrics {

struct GroundTruthLoop {
  double query_timestamp_s = 0.0;  ///< the later frame
  double match_timestamp_s = 0.0;  ///< the earlier frame it revisits
  long long query_index = 0;       ///< frame index (line of rgb.txt from 0)
  long long match_index = 0;
  std::size_t line = 0;  ///< line in the file, for messages
};

inline std::vector<GroundTruthLoop> read_ground_truth_loops(std::istream& in, const std::string& source) {
  std::vector<GroundTruthLoop> loops;
  detail::LineReader reader(in, source);
  std::string line;
  while (reader.next(line)) {
    if (detail::is_blank_or_comment(line)) continue;
    const std::vector<std::string_view> f = detail::split_blank_or_comma(line);
    if (f.size() != 4) {
      reader.fail("expected 4 fields (query_timestamp match_timestamp query_index match_index), found " +
                  std::to_string(f.size()));
    }
    GroundTruthLoop loop;
    loop.line = reader.line_number();
    if (!detail::parse_double(f[0], loop.query_timestamp_s) || !std::isfinite(loop.query_timestamp_s)) {
      reader.fail("query_timestamp " + detail::quoted(f[0]) + " is not a finite number");
    }
    if (!detail::parse_double(f[1], loop.match_timestamp_s) || !std::isfinite(loop.match_timestamp_s)) {
      reader.fail("match_timestamp " + detail::quoted(f[1]) + " is not a finite number");
    }
    if (!detail::parse_count(f[2], loop.query_index)) {
      reader.fail("query_index " + detail::quoted(f[2]) + " is not a non-negative whole number");
    }
    if (!detail::parse_count(f[3], loop.match_index)) {
      reader.fail("match_index " + detail::quoted(f[3]) + " is not a non-negative whole number");
    }
    if (!(loop.match_index < loop.query_index)) {
      reader.fail("match_index " + std::string(f[3]) + " is not smaller than query_index " + std::string(f[2]));
    }
    if (!(loop.match_timestamp_s < loop.query_timestamp_s)) {
      reader.fail("match_timestamp " + std::string(f[1]) + " is not earlier than query_timestamp " + std::string(f[0]));
    }
    loops.push_back(loop);
  }
  return loops;
}

inline std::vector<GroundTruthLoop> read_ground_truth_loops_file(const std::string& path) {
  std::ifstream file = detail::open_input_file(path);
  return read_ground_truth_loops(file, path);
}

}  // namespace metrics
}  // namespace cge
