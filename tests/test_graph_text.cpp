// Text readers: the edge list and point list formats of cge/io/graph_text.hpp.
#include <catch2/catch.hpp>

#include <clocale>
#include <limits>
#include <sstream>
#include <string>

#include "cge/io/graph_text.hpp"
#include "cge/metrics/text_input.hpp"

namespace {

using cge::io::EdgeListOptions;
using cge::io::ParseError;

cge::Graph<double> edges_from(const std::string& text, const EdgeListOptions& options = {}) {
  std::istringstream in(text);
  return cge::io::read_edge_list(in, "test.txt", options);
}

cge::io::PointList points_from(const std::string& text) {
  std::istringstream in(text);
  return cge::io::read_point_list(in, "pts.txt");
}

/// Runs `parse` and returns the ParseError it must throw.
template <typename F>
ParseError parse_error_of(F&& parse) {
  try {
    parse();
  } catch (const ParseError& e) {
    return e;
  }
  FAIL("no ParseError was thrown");
  return ParseError("", 0, "");
}

ParseError edge_error(const std::string& text, const EdgeListOptions& options = {}) {
  return parse_error_of([&] { edges_from(text, options); });
}

ParseError point_error(const std::string& text) {
  return parse_error_of([&] { points_from(text); });
}

}  // namespace

TEST_CASE("edge list: unweighted, comments and blank lines", "[graph_text]") {
  const auto g = edges_from(
      "# a star K_{1,4}\n"
      "\n"
      "0 1\n"
      "   0\t2   # trailing comment\n"
      "#0 9\n"
      "3 0\r\n"
      "0 4#no space before the comment\n"
      "   \t  \n");
  CHECK(g.num_nodes() == 5);
  CHECK(g.num_edges() == 4);
  CHECK_FALSE(g.weighted());
  CHECK(g.degree(0) == 4);
  for (const auto& e : g.edges()) CHECK(e.weight == 1.0);
  CHECK(g.edges()[2].u == 0);
  CHECK(g.edges()[2].v == 3);  // canonical: u < v whatever the input order
}

TEST_CASE("edge list: weights", "[graph_text]") {
  const auto g = edges_from("0 1 1\n1 2 1.0\n2 3 +1e0\n3 0 1\n0 2 1.4142135623730951\n1 3 0\n");
  CHECK(g.weighted());
  CHECK(g.num_nodes() == 4);
  REQUIRE(g.num_edges() == 6);
  CHECK(g.edges()[1].u == 0);
  CHECK(g.edges()[1].v == 2);
  CHECK(g.edges()[1].weight == 1.4142135623730951);
  const auto z = edges_from("0 1 -0\n");  // negative zero is zero
  CHECK(z.edges()[0].weight == 0.0);
  CHECK_FALSE(std::signbit(z.edges()[0].weight));
}

TEST_CASE("edge list: vertex count is max id + 1, unmentioned ids are isolated", "[graph_text]") {
  const auto g = edges_from("0 1\n5 1\n");
  CHECK(g.num_nodes() == 6);
  CHECK(g.degree(3) == 0);
  CHECK(g.degree(1) == 2);
}

TEST_CASE("edge list: empty input gives the empty graph", "[graph_text]") {
  CHECK(edges_from("").num_nodes() == 0);
  CHECK(edges_from("# nothing\n\n   \n").num_nodes() == 0);
  CHECK(edges_from("# nothing\n\n   \n").num_edges() == 0);
}

TEST_CASE("edge list: byte order mark on line 1 is skipped", "[graph_text]") {
  CHECK(edges_from("\xEF\xBB\xBF"
                   "0 1\n")
            .num_edges() == 1);
  // ...but nowhere else.
  CHECK(edge_error("0 1\n\xEF\xBB\xBF"
                   "1 2\n")
            .line() == 2);
}

TEST_CASE("edge list: one-based ids", "[graph_text]") {
  EdgeListOptions one;
  one.one_based = true;
  const auto g = edges_from("1 2\n1 3\n1 4\n1 5\n", one);
  CHECK(g.num_nodes() == 5);
  CHECK(g.degree(0) == 4);
  const auto e = edge_error("1 2\n0 2\n", one);
  CHECK(e.line() == 2);
  CHECK_THAT(e.what(),
             Catch::StartsWith("test.txt:2: ") && Catch::Contains("vertex id 0") && Catch::Contains("one-based"));
  // Messages show the ids as written.
  const auto r = edge_error("1 2\n2 1\n", one);
  CHECK_THAT(r.what(), Catch::Contains("edge 2 1 repeats the edge between 1 and 2 on line 1"));
}

TEST_CASE("edge list: ParseError carries source, line and reason", "[graph_text]") {
  const auto e = edge_error("0 1\n1 2\n2\n");
  CHECK(e.source() == "test.txt");
  CHECK(e.line() == 3);
  CHECK(std::string(e.what()) == "test.txt:3: " + e.reason());
  CHECK_THAT(e.reason(), Catch::Contains("got 1 field"));
  const std::invalid_argument& base = e;          // invalid input, as every reader reports it
  const cge::metrics::ParseError& same_type = e;  // one ParseError for every text reader
  CHECK(&same_type == &e);
  CHECK_THAT(base.what(), Catch::StartsWith("test.txt:3:"));
  std::istringstream in("0 x\n");
  try {
    cge::io::read_edge_list(in);
    FAIL("no throw");
  } catch (const ParseError& err) {
    CHECK(err.source() == "<stdin>");
    CHECK_THAT(err.what(), Catch::StartsWith("<stdin>:1: "));
  }
}

TEST_CASE("edge list: field count errors", "[graph_text]") {
  CHECK_THAT(edge_error("0 1 2 3\n").what(), Catch::StartsWith("test.txt:1: ") && Catch::Contains("got 4 fields"));
  CHECK_THAT(edge_error("# c\n\n7\n").what(), Catch::StartsWith("test.txt:3: ") && Catch::Contains("got 1 field"));
  CHECK_THAT(edge_error("0 1\n0 1 # 2 3 4\n1 2 3 4 # x\n").what(), Catch::StartsWith("test.txt:2: "));
}

TEST_CASE("edge list: bad vertex ids", "[graph_text]") {
  CHECK_THAT(edge_error("0 -1\n").what(), Catch::StartsWith("test.txt:1: ") && Catch::Contains("'-1' is negative"));
  CHECK_THAT(edge_error("0 1\na 1\n").what(),
             Catch::StartsWith("test.txt:2: ") && Catch::Contains("'a' is not a non-negative integer"));
  CHECK_THAT(edge_error("1.5 2\n").what(), Catch::Contains("'1.5' is not a non-negative integer"));
  CHECK_THAT(edge_error("+1 2\n").what(), Catch::Contains("'+1' is not a non-negative integer"));
  CHECK_THAT(edge_error("0x1 2\n").what(), Catch::Contains("'0x1'"));
  CHECK_THAT(edge_error("0 99999999999999999999999\n").what(), Catch::Contains("is too large"));
  EdgeListOptions small;
  small.max_vertices = 10;
  CHECK(edges_from("0 9\n", small).num_nodes() == 10);
  CHECK_THAT(edge_error("0 10\n", small).what(), Catch::StartsWith("test.txt:1: ") && Catch::Contains("at most 9"));
  small.one_based = true;
  CHECK(edges_from("1 10\n", small).num_nodes() == 10);
  CHECK_THAT(edge_error("1 11\n", small).what(), Catch::Contains("at most 10"));
  EdgeListOptions none;
  none.max_vertices = 0;
  std::istringstream in("0 1\n");
  CHECK_THROWS_AS(cge::io::read_edge_list(in, "x", none), std::invalid_argument);
}

TEST_CASE("edge list: bad weights", "[graph_text]") {
  CHECK_THAT(edge_error("0 1 -1\n").what(), Catch::StartsWith("test.txt:1: ") && Catch::Contains("'-1' is negative"));
  CHECK_THAT(edge_error("0 1 abc\n").what(), Catch::Contains("weight 'abc' is not a finite number"));
  CHECK_THAT(edge_error("0 1 inf\n").what(), Catch::Contains("weight 'inf' is not a finite number"));
  CHECK_THAT(edge_error("0 1 nan\n").what(), Catch::Contains("weight 'nan' is not a finite number"));
  CHECK_THAT(edge_error("0 1 1e999\n").what(), Catch::Contains("weight '1e999' is not a finite number"));
  CHECK_THAT(edge_error("0 1 1,5\n").what(), Catch::Contains("'1,5'"));
  CHECK_THAT(edge_error("0 1 2.5x\n").what(), Catch::Contains("'2.5x'"));
  CHECK_THAT(edge_error("0 1 +-1\n").what(), Catch::Contains("'+-1'"));
}

TEST_CASE("edge list: weights on some lines only", "[graph_text]") {
  const auto a = edge_error("# header\n0 1 2.0\n1 2\n");
  CHECK(a.line() == 3);
  CHECK_THAT(a.what(), Catch::StartsWith("test.txt:3: ") && Catch::Contains("no weight") &&
                           Catch::Contains("first edge (line 2) has one"));
  const auto b = edge_error("0 1\n1 2\n2 3 1\n");
  CHECK(b.line() == 3);
  CHECK_THAT(b.what(), Catch::Contains("has a weight") && Catch::Contains("first edge (line 1) has none"));
}

TEST_CASE("edge list: self-loops", "[graph_text]") {
  const auto e = edge_error("0 1\n2 2\n");
  CHECK(e.line() == 2);
  CHECK_THAT(e.what(), Catch::StartsWith("test.txt:2: ") && Catch::Contains("edge 2 2 is a self-loop"));
}

TEST_CASE("edge list: repeated edges name both lines", "[graph_text]") {
  const auto same = edge_error("0 1\n1 2\n# c\n1 2\n");
  CHECK(same.line() == 4);
  CHECK_THAT(same.what(), Catch::StartsWith("test.txt:4: ") &&
                              Catch::Contains("edge 1 2 repeats the edge between 1 and 2 on line 2"));
  const auto reversed = edge_error("0 1\n1 2\n2 1\n");
  CHECK(reversed.line() == 3);
  CHECK_THAT(reversed.what(), Catch::Contains("edge 2 1 repeats the edge between 1 and 2 on line 2"));
  const auto weighted = edge_error("3 5 1\n5 3 2\n");
  CHECK_THAT(weighted.what(), Catch::StartsWith("test.txt:2: ") && Catch::Contains("on line 1"));
}

TEST_CASE("edge list: numbers do not depend on the global C locale", "[graph_text]") {
  // A host program may switch LC_NUMERIC to a comma locale; the reader must still read "0.5".
  const char* previous = std::setlocale(LC_NUMERIC, nullptr);
  const std::string saved = previous ? previous : "C";
  std::setlocale(LC_NUMERIC, "de_DE.UTF-8");  // may be unavailable; then this checks the "C" locale
  const auto g = edges_from("0 1 0.5\n");
  std::setlocale(LC_NUMERIC, saved.c_str());
  CHECK(g.edges()[0].weight == 0.5);
}

TEST_CASE("edge list: read error is reported", "[graph_text]") {
  std::istringstream in("0 1\n");
  in.setstate(std::ios::badbit);
  try {
    cge::io::read_edge_list(in, "broken");
    FAIL("no throw");
  } catch (const ParseError& e) {
    CHECK_THAT(e.what(), Catch::StartsWith("broken:1: ") && Catch::Contains("read error"));
  }
}

TEST_CASE("point list: features and semantic centres", "[graph_text]") {
  const auto p = points_from(
      "# x y [kind]\n"
      "10 20\n"
      "\n"
      "30.5 40.25 feature   # explicit kind\n"
      "320 240 semantic\n"
      "1e2\t+2e2\n");
  REQUIRE(p.points.size() == 3);
  REQUIRE(p.instances.size() == 1);
  CHECK(p.points[0] == Eigen::Vector2d(10, 20));
  CHECK(p.points[1] == Eigen::Vector2d(30.5, 40.25));
  CHECK(p.points[2] == Eigen::Vector2d(100, 200));
  CHECK(p.point_lines == std::vector<std::size_t>{2, 4, 6});
  CHECK(p.instances[0].centre_px == Eigen::Vector2d(320, 240));
  CHECK_FALSE(p.instances[0].dynamic);
  CHECK(p.instances[0].class_id == 0);
  CHECK(p.instance_lines == std::vector<std::size_t>{5});
  const auto empty = points_from("# none\n");
  CHECK(empty.points.empty());
  CHECK(empty.instances.empty());
}

TEST_CASE("point list: errors name source and line", "[graph_text]") {
  CHECK_THAT(point_error("1 2\n3\n").what(), Catch::StartsWith("pts.txt:2: ") && Catch::Contains("got 1 field"));
  CHECK_THAT(point_error("1 2 feature extra\n").what(),
             Catch::StartsWith("pts.txt:1: ") && Catch::Contains("got 4 fields"));
  CHECK_THAT(point_error("1 2\n\n3 4 person\n").what(), Catch::StartsWith("pts.txt:3: ") &&
                                                            Catch::Contains("unknown point kind 'person'") &&
                                                            Catch::Contains("'feature' or 'semantic'"));
  CHECK_THAT(point_error("1 2 Semantic\n").what(), Catch::Contains("'Semantic'"));  // case matters
  CHECK_THAT(point_error("x 2\n").what(), Catch::Contains("x coordinate 'x' is not a finite number"));
  CHECK_THAT(point_error("1 nan\n").what(), Catch::Contains("y coordinate 'nan' is not a finite number"));
  CHECK_THAT(point_error("1 -inf\n").what(), Catch::Contains("y coordinate '-inf'"));
  const auto e = point_error("0 0\n1 2,5\n");
  CHECK(e.source() == "pts.txt");
  CHECK(e.line() == 2);
}
