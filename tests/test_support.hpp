#pragma once
// Helpers shared by the test files (one test executable, so plain inline functions).

#include <catch2/catch.hpp>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "cge/graph/graph.hpp"

namespace cge_test {

/// The message of the std::invalid_argument thrown by f; fails the test when f throws nothing or
/// something else.
template <typename F>
std::string invalid_argument_message(F&& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  } catch (...) {
    FAIL("threw something other than std::invalid_argument");
  }
  FAIL("did not throw");
  return {};
}

/// Connectivity by a depth-first search of our own, independent of the code under test.
inline bool is_connected(const cge::Graph<double>& g) {
  if (g.num_nodes() == 0) return true;
  std::vector<char> seen(static_cast<std::size_t>(g.num_nodes()), 0);
  std::vector<std::int32_t> stack{0};
  seen[0] = 1;
  std::int32_t count = 1;
  while (!stack.empty()) {
    const std::int32_t u = stack.back();
    stack.pop_back();
    for (const std::int32_t w : g.neighbors(u)) {
      if (!seen[static_cast<std::size_t>(w)]) {
        seen[static_cast<std::size_t>(w)] = 1;
        ++count;
        stack.push_back(w);
      }
    }
  }
  return count == g.num_nodes();
}

}  // namespace cge_test
