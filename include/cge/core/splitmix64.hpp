#pragma once
// splitmix64 (G. L. Steele, D. Lea, C. H. Flood, "Fast splittable pseudorandom number generators",
// OOPSLA 2014; S. Vigna's splitmix64.c): the one seeded mixer of the project. Every seeded choice
// (per-frame seeds, simulated segmentation errors, scene variation, per-pixel noise keys, hash
// buckets) goes through it, so one published sequence pins them all.

#include <cstdint>

namespace cge {

/// The generator's state step, the golden ratio times 2^64.
inline constexpr std::uint64_t kSplitMix64Increment = 0x9E3779B97F4A7C15ULL;

/// splitmix64's output function (two xor-shift-multiply rounds and a final xor-shift): a bijection
/// of 64-bit words that spreads every input bit over the whole word.
constexpr std::uint64_t splitmix64_mix(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

/// The n-th output (n = 1, 2, ...) of a SplitMix64 seeded with `seed`, without stepping through the
/// earlier ones: the state after n steps is seed + n x increment (mod 2^64).
constexpr std::uint64_t splitmix64_nth(std::uint64_t seed, std::uint64_t n) {
  return splitmix64_mix(seed + n * kSplitMix64Increment);
}

/// Stateless hash: the first output of a SplitMix64 seeded with x.
constexpr std::uint64_t splitmix64(std::uint64_t x) { return splitmix64_nth(x, 1); }

/// The generator: each call advances the state by the increment and returns its mix.
class SplitMix64 {
 public:
  constexpr explicit SplitMix64(std::uint64_t seed) : state_(seed) {}
  constexpr std::uint64_t next() {
    state_ += kSplitMix64Increment;
    return splitmix64_mix(state_);
  }
  /// Uniform in [0, 1): the top 53 bits of the next output over 2^53.
  constexpr double next_unit() { return static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0); }
  constexpr std::uint64_t state() const { return state_; }

 private:
  std::uint64_t state_;
};

}  // namespace cge
