#pragma once
// Reader of the loop closer's log, loops.csv, written by cge_slam (format fixed in the issue-5
// brief and docs/EVALUATION.md):
//   query_timestamp,match_timestamp,query_keyframe,match_keyframe,bow_score,cge_score,matched_points,accepted,reason
// The first non-blank line must be exactly that header; then one row per keyframe the loop closer
// processed, 9 comma-separated fields:
//   - query_timestamp: finite number; query_keyframe: non-negative whole number;
//   - match_timestamp, match_keyframe, bow_score, cge_score, matched_points: empty when there was
//     no candidate, else a finite number / non-negative whole numbers;
//   - accepted: 0 or 1; reason: one word of lower-case letters and '_' (accepted, no_candidates,
//     low_score, continuity, too_few_matches, pose_not_robust); accepted is 1 exactly when the
//     reason is "accepted", and an accepted row has a match.
// The header may go on with three more columns (the extended format; a file is read
// in the format its header names, every row with that header's field count):
//   ...,reason,tentative_matches,verified_keyframes,connected_keyframes
//   - tentative_matches, verified_keyframes: non-negative whole numbers (descriptor matches before
//     RANSAC of the reported check; geometric checks run);
//   - connected_keyframes: the keyframe ids covisible with the query when it was processed (never
//     candidates), ascending, separated by single spaces; empty for none.
// The loop closer processes each keyframe once: a query_keyframe given on two rows is an error
// (a duplicated row would otherwise count twice).
// Lines that are blank or start with '#' are skipped. A malformed line throws ParseError.

#include <cmath>
#include <cstddef>
#include <istream>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "cge/metrics/text_input.hpp"

namespace cge {
namespace metrics {

/// One row of loops.csv.
struct LoopQuery {
  double query_timestamp_s = 0.0;
  std::optional<double> match_timestamp_s;  ///< empty: no candidate
  long long query_keyframe = 0;
  std::optional<long long> match_keyframe;
  std::optional<double> bow_score;
  std::optional<double> cge_score;
  std::optional<long long> matched_points;
  bool accepted = false;
  std::string reason;
  std::size_t line = 0;  ///< line in the file, for messages
  // Extended format only (empty when the file has the 9 original columns):
  std::optional<long long> tentative_matches;
  std::optional<long long> verified_keyframes;
  std::optional<std::vector<long long>> connected_keyframes;  ///< ascending keyframe ids
};

inline constexpr const char* kLoopQueriesHeader =
    "query_timestamp,match_timestamp,query_keyframe,match_keyframe,bow_score,cge_score,matched_points,accepted,"
    "reason";
/// The extended header: kLoopQueriesHeader followed by these columns.
inline constexpr const char* kLoopQueriesExtraColumns = ",tentative_matches,verified_keyframes,connected_keyframes";

inline std::vector<LoopQuery> read_loop_queries(std::istream& in, const std::string& source) {
  std::vector<LoopQuery> rows;
  std::unordered_map<long long, std::size_t> line_of_query;  // query_keyframe -> its row's line
  detail::LineReader reader(in, source);
  std::string line;
  bool header_seen = false;
  std::size_t fields = 9;  // 12 in the extended format
  auto optional_number = [&reader](std::string_view field, const char* name) -> std::optional<double> {
    if (field.empty()) return std::nullopt;
    double v = 0.0;
    if (!detail::parse_double(field, v) || !std::isfinite(v)) {
      reader.fail(std::string(name) + " " + detail::quoted(field) + " is not a finite number");
    }
    return v;
  };
  auto optional_count = [&reader](std::string_view field, const char* name) -> std::optional<long long> {
    if (field.empty()) return std::nullopt;
    long long v = 0;
    if (!detail::parse_count(field, v)) {
      reader.fail(std::string(name) + " " + detail::quoted(field) + " is not a non-negative whole number");
    }
    return v;
  };
  while (reader.next(line)) {
    if (detail::is_blank_or_comment(line)) continue;
    const std::vector<std::string_view> f = detail::split_csv(line);
    if (!header_seen) {
      std::string joined;
      for (std::size_t i = 0; i < f.size(); ++i) joined += (i ? "," : "") + std::string(f[i]);
      const std::string extended = std::string(kLoopQueriesHeader) + kLoopQueriesExtraColumns;
      if (joined == extended) {
        fields = 12;
      } else if (joined != kLoopQueriesHeader) {
        reader.fail("expected the header '" + std::string(kLoopQueriesHeader) + "' (optionally followed by '" +
                    kLoopQueriesExtraColumns + "')");
      }
      header_seen = true;
      continue;
    }
    if (f.size() != fields) {
      reader.fail("expected " + std::to_string(fields) + " comma-separated fields, found " + std::to_string(f.size()));
    }
    LoopQuery row;
    row.line = reader.line_number();
    const std::optional<double> query = optional_number(f[0], "query_timestamp");
    if (!query) reader.fail("query_timestamp is empty");
    row.query_timestamp_s = *query;
    row.match_timestamp_s = optional_number(f[1], "match_timestamp");
    const std::optional<long long> query_keyframe = optional_count(f[2], "query_keyframe");
    if (!query_keyframe) reader.fail("query_keyframe is empty");
    row.query_keyframe = *query_keyframe;
    const auto first = line_of_query.emplace(row.query_keyframe, row.line);
    if (!first.second) {
      reader.fail("query_keyframe " + std::to_string(row.query_keyframe) + " repeats the row on line " +
                  std::to_string(first.first->second) + " (each keyframe is queried once)");
    }
    row.match_keyframe = optional_count(f[3], "match_keyframe");
    row.bow_score = optional_number(f[4], "bow_score");
    row.cge_score = optional_number(f[5], "cge_score");
    row.matched_points = optional_count(f[6], "matched_points");
    if (f[7] != "0" && f[7] != "1") reader.fail("accepted " + detail::quoted(f[7]) + " is not 0 or 1");
    row.accepted = f[7] == "1";
    if (f[8].empty()) reader.fail("reason is empty");
    for (const char c : f[8]) {
      if (!((c >= 'a' && c <= 'z') || c == '_')) {
        reader.fail("reason " + detail::quoted(f[8]) + " is not one word of lower-case letters and '_'");
      }
    }
    row.reason = std::string(f[8]);
    if (row.accepted != (row.reason == "accepted")) {
      reader.fail("accepted is " + std::string(f[7]) + " but the reason is '" + row.reason + "'");
    }
    if (row.accepted && !(row.match_timestamp_s && row.match_keyframe)) {
      reader.fail("an accepted row needs match_timestamp and match_keyframe");
    }
    if (row.match_timestamp_s.has_value() != row.match_keyframe.has_value()) {
      reader.fail("match_timestamp and match_keyframe must be both given or both empty");
    }
    if (fields == 12) {
      row.tentative_matches = optional_count(f[9], "tentative_matches");
      row.verified_keyframes = optional_count(f[10], "verified_keyframes");
      if (!row.tentative_matches || !row.verified_keyframes) {
        reader.fail("tentative_matches and verified_keyframes must not be empty");
      }
      std::vector<long long> ids;
      std::string_view rest = f[11];
      while (!rest.empty()) {
        const std::size_t space = rest.find(' ');
        const std::string_view id_text = rest.substr(0, space);
        long long id = 0;
        if (!detail::parse_count(id_text, id)) {
          reader.fail("connected_keyframes " + detail::quoted(f[11]) +
                      " is not a list of non-negative whole numbers separated by single spaces");
        }
        if (!ids.empty() && id <= ids.back()) {
          reader.fail("connected_keyframes " + detail::quoted(f[11]) + " is not strictly ascending");
        }
        ids.push_back(id);
        if (space == std::string_view::npos) break;
        rest = rest.substr(space + 1);
        if (rest.empty()) reader.fail("connected_keyframes " + detail::quoted(f[11]) + " ends with a space");
      }
      row.connected_keyframes = std::move(ids);
    }
    rows.push_back(row);
  }
  if (!header_seen) {
    throw ParseError(source, reader.line_number() == 0 ? 1 : reader.line_number(),
                     "no header line (the file is empty)");
  }
  return rows;
}

inline std::vector<LoopQuery> read_loop_queries_file(const std::string& path) {
  std::ifstream file = detail::open_input_file(path);
  return read_loop_queries(file, path);
}

}  // namespace metrics
}  // namespace cge
