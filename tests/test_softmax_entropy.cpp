// Tests of softmax_entropy_bits (cge/entropy/softmax_entropy.hpp): the entropy of exp-weights in
// the log domain, against the plain formula where it works and at weights far beyond double.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "cge/entropy/softmax_entropy.hpp"
#include "degree_entropy_test_support.hpp"

using namespace dde_test;

TEST_CASE("softmax_entropy_bits works in the log domain", "[dde][numerics]") {
  // Two equal weights: 1 bit, however small the weights are.
  CHECK(cge::softmax_entropy_bits({-1e5, -1e5}) == Approx(1.0).epsilon(1e-15));
  CHECK(cge::softmax_entropy_bits({-2e5, -1e5, -1e5, -3e5}) == Approx(1.0).epsilon(1e-15));
  CHECK(cge::softmax_entropy_bits({1e5, 1e5, 1e5, 1e5}) == Approx(2.0).epsilon(1e-15));
  // e^-1e5 against e^-2e5: all mass on the first, H = 0 (the second term is e^-1e5 log e^-1e5).
  const double h = cge::softmax_entropy_bits({-1e5, -2e5});
  CHECK(std::isfinite(h));
  CHECK(h == Approx(0.0).margin(1e-300));
  // p = (1/4, 3/4) encoded with an enormous common offset: H = 2 - (3/4) log2 3.
  const double offset = -1e5;
  CHECK(cge::softmax_entropy_bits({offset, offset + std::log(3.0)}) ==
        Approx(2.0 - 0.75 * std::log2(3.0)).epsilon(1e-9));
  // Against the plain formula where the plain formula works.
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(-20.0, 20.0);
  for (int trial = 0; trial < 100; ++trial) {
    std::vector<double> logs(static_cast<std::size_t>(1 + trial % 17));
    for (double& l : logs) l = u(rng);
    LD z = 0;
    for (double l : logs) z += std::exp(static_cast<LD>(l));
    LD expected = 0;
    for (double l : logs) {
      const LD p = std::exp(static_cast<LD>(l)) / z;
      expected -= p * std::log2(p);
    }
    CHECK(close(cge::softmax_entropy_bits(logs), expected, 1e-13L));
  }
  CHECK(cge::softmax_entropy_bits({42.0}) == 0.0);
  CHECK_THROWS_AS(cge::softmax_entropy_bits({}), std::invalid_argument);
  CHECK_THROWS_AS(cge::softmax_entropy_bits({0.0, std::numeric_limits<double>::infinity()}), std::overflow_error);
  CHECK_THROWS_AS(cge::softmax_entropy_bits({0.0, -std::numeric_limits<double>::infinity()}), std::overflow_error);
  CHECK_THROWS_AS(cge::softmax_entropy_bits({std::numeric_limits<double>::quiet_NaN()}), std::overflow_error);
}
