#pragma once
// Delta(v, k) of docs/METHOD.md section 4: over the shortest paths of length k that start at v, the
// sums of absolute degree differences along the path, computed exactly in O(|V| |E|) by a BFS
// dynamic programme from every source, without listing paths.
//
// For a source s and every node u (predecessors p of u have dist(p) = dist(u) - 1):
//   N[u] = sum_p N[p]                               number of shortest s-u paths
//   S[u] = sum_p (S[p] + N[p] |d(p) - d(u)|)        sum over those paths of their degree sums
//   M[u] = min_p (M[p] + |d(p) - d(u)|)             smallest degree sum over those paths
// and Delta(s, k) sums, over the nodes u at distance k, S[u] (TieMode::all), S[u] / N[u]
// (TieMode::mean) or M[u] (TieMode::min). All three depend only on the graph, never on node
// numbering (up to floating-point rounding, as relabelling changes the summation order).
// N and S are kept in double: path counts grow exponentially on tie-rich graphs.
// The sweep runs 64 sources at once, one bit per source: the same O(|V| |E|) arithmetic, but the
// BFS bookkeeping costs one word operation per 64 sources. Two kernels implement it with the same
// operations in the same order, so their tables agree bit for bit (and with the plain code of
// reference_degree_degree_entropy.hpp):
//   - portable (kernels/block_bfs.hpp): plain C++;
//   - avx512 (kernels/block_bfs_avx512.hpp): compact per-level values, 8 sources per instruction,
//     chosen at run time on x86-64 CPUs that support it.

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "cge/entropy/degree_sum_table.hpp"
#include "cge/entropy/kernels/block_bfs.hpp"
#include "cge/entropy/kernels/block_bfs_avx512.hpp"
#include "cge/graph/graph.hpp"

namespace cge {

/// True when `kernel` can run here (automatic and portable always can).
inline bool degree_sum_kernel_available(DegreeSumKernel kernel) {
  return kernel != DegreeSumKernel::avx512 || detail::avx512_degree_sums_supported();
}

namespace detail {

template <typename Sweep, typename Scalar>
void fill_table(const Graph<Scalar>& g, DegreeSumTable& table) {
  const std::int32_t n = g.num_nodes();
  const std::vector<std::int32_t> order = local_source_order(g);
  Sweep sweep(g);
  // Rows arrive block by block; they are staged in one buffer (the 64 block rows keep their
  // storage) and copied into source order at the end.
  std::vector<std::vector<double>> block_rows(64);
  std::vector<double> staged;
  std::vector<std::int64_t> staged_at(static_cast<std::size_t>(n) + 1, 0);
  std::vector<std::int32_t> row_length(static_cast<std::size_t>(n), 0);
  for (std::size_t first = 0; first < order.size(); first += 64) {
    const int lanes = static_cast<int>(std::min<std::size_t>(64, order.size() - first));
    const std::int64_t reached = sweep.run(order.data() + first, lanes, block_rows);
    if (reached < static_cast<std::int64_t>(lanes) * n) table.connected = false;
    for (int i = 0; i < lanes; ++i) {
      const std::size_t s = static_cast<std::size_t>(order[first + static_cast<std::size_t>(i)]);
      const std::vector<double>& row = block_rows[static_cast<std::size_t>(i)];
      staged_at[s] = static_cast<std::int64_t>(staged.size());
      row_length[s] = static_cast<std::int32_t>(row.size());
      staged.insert(staged.end(), row.begin(), row.end());
    }
  }
  table.values.resize(staged.size());
  table.row_offsets.assign(static_cast<std::size_t>(n) + 1, 0);
  std::int64_t at = 0;
  for (std::size_t s = 0; s < static_cast<std::size_t>(n); ++s) {
    std::copy_n(staged.begin() + staged_at[s], row_length[s], table.values.begin() + at);
    at += row_length[s];
    table.row_offsets[s + 1] = at;
    table.diameter = std::max(table.diameter, row_length[s]);
  }
}

template <TieMode Mode, typename Scalar>
void fill_table(const Graph<Scalar>& g, DegreeSumTable& table, bool use_avx512) {
#if CGE_DEGREE_SUMS_HAVE_AVX512
  if (use_avx512) {
    fill_table<BlockBfsDegreeSumsAvx512<Mode, Scalar>>(g, table);
    return;
  }
#else
  (void)use_avx512;
#endif
  fill_table<BlockBfsDegreeSums<Mode, Scalar>>(g, table);
}

}  // namespace detail

/// Delta(s, k) for every source and distance. Throws std::invalid_argument on an empty graph, or
/// when `kernel` is avx512 and this CPU cannot run it (see degree_sum_kernel_available). Every
/// kernel returns the same table, bit for bit.
template <typename Scalar>
DegreeSumTable shortest_path_degree_sums(const Graph<Scalar>& g, TieMode ties = TieMode::all,
                                         DegreeSumKernel kernel = DegreeSumKernel::automatic) {
  detail::require_nodes(g.num_nodes());
  if (!degree_sum_kernel_available(kernel)) {
    throw std::invalid_argument(
        "shortest_path_degree_sums: the avx512 kernel needs an x86-64 CPU with AVX-512 F, BW, VL, VBMI2 and "
        "VPOPCNTDQ, and a GCC or Clang build");
  }
  const bool use_avx512 = kernel == DegreeSumKernel::avx512 ||
                          (kernel == DegreeSumKernel::automatic && detail::avx512_degree_sums_supported());
  DegreeSumTable table;
  table.num_nodes = g.num_nodes();
  detail::with_tie_mode(ties, [&](auto mode) { detail::fill_table<decltype(mode)::value>(g, table, use_avx512); });
  return table;
}

}  // namespace cge
