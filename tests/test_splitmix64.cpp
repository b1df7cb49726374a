// splitmix64 against the published reference sequences (Rosetta Code, "Pseudo-random
// numbers/Splitmix64", which reproduces Vigna's splitmix64.c), and its three entry points against
// each other.
#include <catch2/catch.hpp>

#include <cstdint>

#include "cge/core/splitmix64.hpp"

TEST_CASE("SplitMix64 reproduces the reference sequence of seed 1234567", "[splitmix64]") {
  cge::SplitMix64 rng(1234567);
  CHECK(rng.next() == 6457827717110365317ULL);
  CHECK(rng.next() == 3203168211198807973ULL);
  CHECK(rng.next() == 9817491932198370423ULL);
  CHECK(rng.next() == 4593380528125082431ULL);
  CHECK(rng.next() == 16408922859458223821ULL);
}

TEST_CASE("SplitMix64 reproduces the reference outputs of seed 0", "[splitmix64]") {
  cge::SplitMix64 rng(0);
  CHECK(rng.next() == 0xE220A8397B1DCDAFULL);
  CHECK(rng.next() == 0x6E789E6AA1B965F4ULL);
  CHECK(rng.next() == 0x06C45D188009454FULL);
  CHECK(rng.next() == 0xF88BB8A8724C81ECULL);
  CHECK(rng.next() == 0x1B39896A51A8749BULL);
  // The state wraps modulo 2^64: seed 2^64 - 1 and -1 are one generator.
  cge::SplitMix64 a(~std::uint64_t{0});
  CHECK(a.next() == 0xE4D971771B652C20ULL);
  CHECK(a.next() == 0xE99FF867DBF682C9ULL);
}

TEST_CASE("splitmix64 and splitmix64_nth are the generator's outputs", "[splitmix64]") {
  for (const std::uint64_t seed : {std::uint64_t{0}, std::uint64_t{1234567}, ~std::uint64_t{0}, std::uint64_t{42}}) {
    cge::SplitMix64 rng(seed);
    CHECK(cge::splitmix64(seed) == cge::SplitMix64(seed).next());
    for (std::uint64_t n = 1; n <= 100; ++n) {
      const std::uint64_t expected = rng.next();
      CHECK(cge::splitmix64_nth(seed, n) == expected);
      CHECK(cge::splitmix64_mix(rng.state()) == expected);
    }
  }
  static_assert(cge::splitmix64(1234567) == 6457827717110365317ULL, "usable in constant expressions");
}

TEST_CASE("SplitMix64::next_unit is the top 53 bits over 2^53", "[splitmix64]") {
  cge::SplitMix64 a(1234567), b(1234567);
  for (int i = 0; i < 1000; ++i) {
    const std::uint64_t word = b.next();
    const double u = a.next_unit();
    CHECK(u == static_cast<double>(word >> 11) / 9007199254740992.0);
    CHECK(u >= 0.0);
    CHECK(u < 1.0);
  }
}
