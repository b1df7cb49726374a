#pragma once
// The result type of shortest_path_degree_sums and its two choices: how tied shortest paths count,
// and which implementation of the sweep runs.

#include <cstdint>
#include <stdexcept>
#include <type_traits>
#include <vector>

namespace cge {

/// How several shortest paths between the same two nodes count in Delta.
enum class TieMode {
  all,   ///< every shortest path counts with its own sum (multiplicity; the default)
  mean,  ///< one averaged path per end node: the mean sum over its shortest paths
  min,   ///< one path per end node: the shortest path with the smallest sum
};

namespace detail {

/// The degree-degree entropy is undefined on an empty graph (docs/METHOD.md section 4): one message
/// for every entry point.
inline void require_nodes(std::int32_t num_nodes) {
  if (num_nodes == 0) throw std::invalid_argument("degree-degree entropy: the graph has no nodes");
}

/// Calls f(std::integral_constant<TieMode, ties>{}): the run-time tie mode as a compile-time one,
/// for the kernels that are templates on it.
template <typename F>
decltype(auto) with_tie_mode(TieMode ties, F&& f) {
  switch (ties) {
    case TieMode::all:
      return f(std::integral_constant<TieMode, TieMode::all>{});
    case TieMode::mean:
      return f(std::integral_constant<TieMode, TieMode::mean>{});
    case TieMode::min:
      break;
  }
  return f(std::integral_constant<TieMode, TieMode::min>{});
}

}  // namespace detail

/// Which implementation of the all-sources sweep computes the table. Every kernel gives the same
/// table, bit for bit: the choice changes only the speed.
enum class DegreeSumKernel {
  automatic,  ///< the fastest kernel this CPU supports (the default)
  portable,   ///< plain C++, any platform
  avx512,     ///< x86-64 with AVX-512 F, BW, VL, VBMI2 and VPOPCNTDQ, chosen at run time
};

/// Delta(s, k) for every source s and k = 1..eccentricity(s), stored row by row.
struct DegreeSumTable {
  std::int32_t num_nodes = 0;
  std::int32_t diameter = 0;              ///< largest finite hop distance
  bool connected = true;                  ///< false when some pair of nodes is unreachable
  std::vector<std::int64_t> row_offsets;  ///< num_nodes + 1 entries into values
  std::vector<double> values;             ///< row s holds Delta(s, 1), ..., Delta(s, ecc(s))

  std::int32_t eccentricity(std::int32_t s) const {
    return static_cast<std::int32_t>(row_offsets[static_cast<std::size_t>(s) + 1] -
                                     row_offsets[static_cast<std::size_t>(s)]);
  }
  /// Delta(s, k) for k >= 1; 0 beyond the eccentricity of s.
  double delta(std::int32_t s, std::int32_t k) const {
    if (k < 1 || k > eccentricity(s)) return 0.0;
    return values[static_cast<std::size_t>(row_offsets[static_cast<std::size_t>(s)] + k - 1)];
  }
};

}  // namespace cge
