#pragma once
// loops.csv parsed from a string, for the tests of the reader and of what reads its rows.

#include <sstream>
#include <string>
#include <vector>

#include "cge/metrics/loop_queries_io.hpp"
#include "test_support.hpp"

namespace cge_test {

/// The rows of `text`, read as a file named loops.csv.
inline std::vector<cge::metrics::LoopQuery> read_loops_csv_text(const std::string& text) {
  std::istringstream in(text);
  return cge::metrics::read_loop_queries(in, "loops.csv");
}

/// The message of the std::invalid_argument that reading `text` throws.
inline std::string loops_csv_error(const std::string& text) {
  return invalid_argument_message([&] { read_loops_csv_text(text); });
}

}  // namespace cge_test
