// Uses the installed cge package: the information index of the path P5 (docs/METHOD.md section 4).
// Exits 0 when it matches the worked value, 1 otherwise.
#include <cmath>
#include <cstdio>

#include <cge/cge.hpp>

int main() {
  const auto p5 = cge::Graph<double>::from_edges(5, {{0, 1}, {1, 2}, {2, 3}, {3, 4}}, /*weighted=*/false);
  const double index = cge::DegreeDegreeEntropy<double>().information_index(p5);
  const double expected = 0.527454699858088;
  std::printf("P5 information index %.15g (expected %.15g)\n", index, expected);
  return std::fabs(index - expected) <= 1e-12 ? 0 : 1;
}
