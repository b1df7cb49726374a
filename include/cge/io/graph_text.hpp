#pragma once
// Plain-text readers for the command-line tools and for tests: an edge list (abstract graphs) and a
// point list (the nodes of a frame graph before GraphBuilder connects them).
//
// Common rules for both formats:
//   - one record per line, fields separated by blanks or tabs (a trailing '\r' is ignored);
//   - '#' starts a comment that runs to the end of the line (whole-line or trailing);
//   - blank and comment-only lines are ignored; a UTF-8 byte order mark on line 1 is skipped;
//   - numbers are read in the "C" locale whatever the global locale is.
// Every malformed line throws cge::io::ParseError (= cge::ParseError, a std::invalid_argument) whose message is
// "<source>:<line>: <problem>", with <source> the name the caller passes (a file name, or "<stdin>").
//
// Edge list ("u v" or "u v w" per line):
//   - u, v: vertex ids, non-negative decimal integers, 0-based unless EdgeListOptions::one_based
//     (then ids start at 1 and 0 is an error); the graph has max id + 1 vertices, so ids that never
//     appear are isolated vertices;
//   - w: a non-negative finite weight; either every edge has one or none does (then the graph is
//     unweighted and every weight is 1);
//   - a self-loop or an edge given twice (in either direction) is an error naming both lines.
// An input without edges gives the empty graph (0 vertices); whether that is acceptable is the
// caller's decision.
//
// Point list ("x y" or "x y kind" per line, pixels):
//   - kind "feature" (the default) is a keypoint; "semantic" is the centre of a static semantic
//     instance (class 0: the text format carries no class);
//   - x, y must be finite; whether they lie in the image is checked by the caller, which knows
//     the image size (the line of every record is kept for its messages).
//
// Standard library and the core only.

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <istream>
#include <locale>
#include <sstream>
#include <stdexcept>
#include <string>
#include <system_error>
#include <unordered_map>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "cge/core/parse_error.hpp"
#include "cge/core/semantic_instance.hpp"
#include "cge/graph/graph.hpp"

namespace cge {
namespace io {

/// A malformed line (or a failed read) in text input: the toolkit's one ParseError
/// (cge/core/parse_error.hpp, a std::invalid_argument), "<source>:<line>: <reason>".
using ParseError = ::cge::ParseError;

struct EdgeListOptions {
  /// Vertex ids start at 1 (as in many graph collections); an id 0 is then an error.
  bool one_based = false;
  /// Largest accepted number of vertices (max id + 1). The graph allocates per vertex, so a stray
  /// huge id would otherwise ask for gigabytes; raise it for genuinely large graphs.
  std::int32_t max_vertices = std::int32_t(1) << 24;
  /// How messages name max_vertices (a tool passes its option, e.g. "--max-vertices").
  std::string max_vertices_name = "EdgeListOptions::max_vertices";
};

/// The records of a point list, in file order.
struct PointList {
  std::vector<Eigen::Vector2d> points;              ///< keypoints ("feature"), pixels
  std::vector<SemanticInstance<double>> instances;  ///< static semantic instance centres ("semantic")
  std::vector<std::size_t> point_lines;             ///< line of each point, parallel to points
  std::vector<std::size_t> instance_lines;          ///< line of each instance, parallel to instances
};

namespace detail {

inline bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/// Splits one line into whitespace-separated fields, dropping a '#' comment. The views point into
/// `line` and stay valid while it does.
inline void split_fields(const std::string& line, std::vector<std::pair<const char*, const char*>>& fields) {
  fields.clear();
  const char* p = line.data();
  const char* end = p + line.size();
  for (const char* q = p; q != end; ++q) {
    if (*q == '#') {
      end = q;
      break;
    }
  }
  while (p != end) {
    while (p != end && is_blank(*p)) ++p;
    if (p == end) break;
    const char* start = p;
    while (p != end && !is_blank(*p)) ++p;
    fields.emplace_back(start, p);
  }
}

inline std::string quoted(const std::pair<const char*, const char*>& field) {
  return "'" + std::string(field.first, field.second) + "'";
}

inline std::string count_fields(std::size_t n) { return std::to_string(n) + (n == 1 ? " field" : " fields"); }

/// Parses a decimal number that must use the whole field; false when it does not parse, does not
/// fit a double, or has trailing characters. Locale-independent. A leading '+' is accepted.
inline bool parse_double(const char* first, const char* last, double& out) {
  if (first != last && *first == '+') {
    ++first;
    if (first != last && (*first == '-' || *first == '+')) return false;
  }
  if (first == last) return false;
#if defined(__cpp_lib_to_chars) && __cpp_lib_to_chars >= 201611L
  const std::from_chars_result r = std::from_chars(first, last, out);
  return r.ec == std::errc() && r.ptr == last;
#else
  std::istringstream in(std::string(first, last));
  in.imbue(std::locale::classic());
  in >> out;
  return !in.fail() && in.peek() == std::char_traits<char>::eof();
#endif
}

/// Reads a vertex id (decimal digits only) and converts it to 0-based; throws ParseError naming
/// the problem.
inline std::int32_t parse_vertex_id(const std::pair<const char*, const char*>& field, const EdgeListOptions& options,
                                    const std::string& source, std::size_t line) {
  const char* first = field.first;
  const char* last = field.second;
  bool digits = first != last;
  for (const char* p = first; p != last; ++p) digits = digits && *p >= '0' && *p <= '9';
  if (!digits) {
    bool negative = last - first > 1 && *first == '-';
    for (const char* p = first + 1; negative && p != last; ++p) negative = *p >= '0' && *p <= '9';
    throw ParseError(source, line,
                     "vertex id " + quoted(field) + (negative ? " is negative" : " is not a non-negative integer"));
  }
  std::uint64_t value = 0;
  const std::from_chars_result r = std::from_chars(first, last, value);
  const std::uint64_t lowest = options.one_based ? 1 : 0;
  if (options.one_based && r.ec == std::errc() && value == 0) {
    throw ParseError(source, line, "vertex id 0 in a one-based edge list (ids start at 1)");
  }
  // The largest 0-based id is max_vertices - 1.
  const std::uint64_t limit = static_cast<std::uint64_t>(options.max_vertices) - 1 + lowest;
  if (r.ec != std::errc() || value > limit) {
    throw ParseError(source, line,
                     "vertex id " + quoted(field) + " is too large (at most " + std::to_string(limit) + ": " +
                         options.max_vertices_name + " is " + std::to_string(options.max_vertices) + ")");
  }
  return static_cast<std::int32_t>(value - lowest);
}

/// Reads lines and hands each non-empty field list with its 1-based line number to `record`.
template <typename Record>
void for_each_record(std::istream& in, const std::string& source, Record&& record) {
  std::string text;
  std::vector<std::pair<const char*, const char*>> fields;
  std::size_t line = 0;
  while (std::getline(in, text)) {
    ++line;
    if (line == 1 && text.compare(0, 3, "\xEF\xBB\xBF") == 0) text.erase(0, 3);
    split_fields(text, fields);
    if (!fields.empty()) record(fields, line);
  }
  if (in.bad()) throw ParseError(source, line + 1, "read error");
}

}  // namespace detail

/// Reads an edge list (format above) into a canonical graph; weighted() tells whether weights were
/// given. Throws ParseError for any malformed line.
inline Graph<double> read_edge_list(std::istream& in, const std::string& source = "<stdin>",
                                    const EdgeListOptions& options = {}) {
  if (options.max_vertices < 1) {
    throw std::invalid_argument("EdgeListOptions: max_vertices must be at least 1");
  }
  const std::int32_t shown_offset = options.one_based ? 1 : 0;  // ids in messages as the user wrote them
  std::vector<Edge<double>> edges;
  std::unordered_map<std::uint64_t, std::size_t> line_of_edge;  // key (min id, max id) -> line
  std::size_t first_edge_line = 0;
  bool weighted = false;
  std::int32_t max_id = -1;

  detail::for_each_record(in, source, [&](const auto& fields, std::size_t line) {
    if (fields.size() != 2 && fields.size() != 3) {
      throw ParseError(source, line,
                       "expected 'u v' or 'u v w' (2 or 3 fields), got " + detail::count_fields(fields.size()));
    }
    const std::int32_t u = detail::parse_vertex_id(fields[0], options, source, line);
    const std::int32_t v = detail::parse_vertex_id(fields[1], options, source, line);
    const bool has_weight = fields.size() == 3;
    double w = 1.0;
    if (has_weight) {
      if (!detail::parse_double(fields[2].first, fields[2].second, w) || !std::isfinite(w)) {
        throw ParseError(source, line, "weight " + detail::quoted(fields[2]) + " is not a finite number");
      }
      if (w < 0) throw ParseError(source, line, "weight " + detail::quoted(fields[2]) + " is negative");
      w = w + 0.0;  // -0 becomes +0
    }
    if (first_edge_line == 0) {
      first_edge_line = line;
      weighted = has_weight;
    } else if (has_weight != weighted) {
      throw ParseError(source, line,
                       std::string(has_weight ? "this edge has a weight but the first edge (line "
                                              : "this edge has no weight but the first edge (line ") +
                           std::to_string(first_edge_line) + (weighted ? ") has one" : ") has none") +
                           ": give every edge a weight or none");
    }
    const std::string written = std::to_string(u + shown_offset) + " " + std::to_string(v + shown_offset);
    if (u == v) throw ParseError(source, line, "edge " + written + " is a self-loop");
    const std::int32_t lo = std::min(u, v);
    const std::int32_t hi = std::max(u, v);
    const std::uint64_t key = (static_cast<std::uint64_t>(lo) << 32) | static_cast<std::uint64_t>(hi);
    const auto inserted = line_of_edge.emplace(key, line);
    if (!inserted.second) {
      throw ParseError(source, line,
                       "edge " + written + " repeats the edge between " + std::to_string(lo + shown_offset) + " and " +
                           std::to_string(hi + shown_offset) + " on line " + std::to_string(inserted.first->second));
    }
    max_id = std::max(max_id, hi);
    edges.push_back(Edge<double>{u, v, w});
  });
  return Graph<double>::from_edges(max_id + 1, std::move(edges), weighted);
}

/// Reads a point list (format above). Throws ParseError for any malformed line.
inline PointList read_point_list(std::istream& in, const std::string& source = "<stdin>") {
  PointList out;
  detail::for_each_record(in, source, [&](const auto& fields, std::size_t line) {
    if (fields.size() != 2 && fields.size() != 3) {
      throw ParseError(source, line,
                       "expected 'x y' or 'x y kind' (2 or 3 fields), got " + detail::count_fields(fields.size()));
    }
    double xy[2] = {0.0, 0.0};
    for (int i = 0; i < 2; ++i) {
      const auto& f = fields[static_cast<std::size_t>(i)];
      if (!detail::parse_double(f.first, f.second, xy[i]) || !std::isfinite(xy[i])) {
        throw ParseError(
            source, line,
            std::string(i == 0 ? "x" : "y") + " coordinate " + detail::quoted(f) + " is not a finite number");
      }
    }
    const Eigen::Vector2d p(xy[0], xy[1]);
    const std::string kind = fields.size() == 3 ? std::string(fields[2].first, fields[2].second) : "feature";
    if (kind == "feature") {
      out.points.push_back(p);
      out.point_lines.push_back(line);
    } else if (kind == "semantic") {
      SemanticInstance<double> inst;
      inst.centre_px = p;
      inst.class_id = 0;
      inst.dynamic = false;
      out.instances.push_back(inst);
      out.instance_lines.push_back(line);
    } else {
      throw ParseError(source, line,
                       "unknown point kind " + detail::quoted(fields[2]) + ": expected 'feature' or 'semantic'");
    }
  });
  return out;
}

}  // namespace io
}  // namespace cge
