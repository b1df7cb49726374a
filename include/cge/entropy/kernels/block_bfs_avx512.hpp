#pragma once
// Block BFS with AVX-512: the kernel of shortest_path_degree_sums on CPUs that have it
// (docs/METHOD.md section 4), chosen at run time.
//
// The same dynamic programme as BlockBfsDegreeSums, for the same blocks of 64 sources, with
// exactly the same floating-point operations in the same order, so the tables agree bit for bit:
//   N[u] = sum_p N[p],  S[u] = sum_p (S[p] + N[p] |d(p) - d(u)|),  M[u] = min_p (M[p] + |d(p) - d(u)|)
// with the predecessors p in ascending node order, and Delta(s, k) summed over the nodes at
// distance k in ascending node order. What differs is the layout and the traversal:
//  - Compact values. A node at level k holds values only for the sources ("lanes") that reach it
//    at distance k, packed in lane order: about 9 of 64 lanes on geometric graphs. A level's
//    values therefore take tens of kilobytes, not 1 KiB per node; only two levels are kept.
//  - Pull, not push. Each node that can be reached at the next level reads the lane masks of its
//    neighbours (its predecessors are the neighbours on the previous level for those lanes) and
//    sums its values at once. The candidates are the "live" nodes: reached by some lanes but not
//    yet by all lanes of its component, plus the unreached neighbours of nodes reached for the
//    first time. Nodes are visited in ascending order, which fixes every summation order.
//  - Eight lanes per instruction. A predecessor's values for eight of the node's lanes are found
//    by their rank in the predecessor's lane mask (a population count) and fetched with one
//    two-register permute (vpermt2pd); the multiply is kept apart from the add (no FMA
//    contraction), so each lane computes exactly what the portable kernel computes.
// Compiled only for x86-64 with GCC or Clang, through target attributes: the including build
// needs no flags, and the kernel runs only after avx512_degree_sums_supported() said yes.

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define CGE_DEGREE_SUMS_HAVE_AVX512 1
#else
#define CGE_DEGREE_SUMS_HAVE_AVX512 0
#endif

#if CGE_DEGREE_SUMS_HAVE_AVX512

#include <immintrin.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "cge/core/bits.hpp"
#include "cge/entropy/degree_sum_table.hpp"
#include "cge/entropy/kernels/mean_rescale.hpp"
#include "cge/graph/graph.hpp"

// The instruction sets the kernel is compiled for (and checked at run time).
#define CGE_DEGREE_SUMS_AVX512_TARGET \
  __attribute__((target("avx512f,avx512bw,avx512vl,avx512vbmi2,avx512vpopcntdq,popcnt")))

namespace cge {
namespace detail {

/// True when this CPU (and operating system) runs the AVX-512 kernel.
inline bool avx512_degree_sums_supported() {
  static const bool supported = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
           __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512vbmi2") &&
           __builtin_cpu_supports("avx512vpopcntdq") && __builtin_cpu_supports("popcnt");
  }();
  return supported;
}

/// Delta rows of up to 64 sources at once with compact per-level values (see the file comment).
/// Same interface as BlockBfsDegreeSums; run() only when avx512_degree_sums_supported().
template <TieMode Mode, typename Scalar>
class BlockBfsDegreeSumsAvx512 {
 public:
  explicit BlockBfsDegreeSumsAvx512(const Graph<Scalar>& g)
      : n_(g.num_nodes()),
        offsets_(g.csr_offsets().data()),
        adjacency_(g.csr_adjacency().data()),
        previous_(static_cast<std::size_t>(n_), 0),
        current_(static_cast<std::size_t>(n_), 0),
        visited_(static_cast<std::size_t>(n_), 0),
        live_((static_cast<std::size_t>(n_) + 63) / 64, 0),
        degree_(static_cast<std::size_t>(n_)),
        component_(static_cast<std::size_t>(n_), -1),
        offset_previous_(static_cast<std::size_t>(n_), 0),
        offset_current_(static_cast<std::size_t>(n_), 0),
        fresh_(static_cast<std::size_t>(n_)) {
    std::int32_t max_degree = 0;
    for (std::int32_t v = 0; v < n_; ++v) {
      degree_[static_cast<std::size_t>(v)] = g.degree(v);
      max_degree = std::max(max_degree, g.degree(v));
    }
    // Room for a whole 16-wide store past the last record.
    pred_mask_.resize(static_cast<std::size_t>(max_degree) + 16);
    pred_node_.resize(static_cast<std::size_t>(max_degree) + 16);
    label_components(g);
    frontier_.reserve(static_cast<std::size_t>(n_));
    next_frontier_.reserve(static_cast<std::size_t>(n_));
    grow(values_previous_, kInitialValues);
    grow(values_current_, kInitialValues);
  }

  /// Runs the sources (at most 64); rows[i] receives Delta(sources[i], 1..ecc). Returns the number
  /// of (source, node) pairs reached.
  std::int64_t run(const std::int32_t* sources, int lanes, std::vector<std::vector<double>>& rows) {
    std::fill(visited_.begin(), visited_.end(), 0);
    frontier_.clear();
    for (int i = 0; i < lanes; ++i) {
      const std::size_t s = static_cast<std::size_t>(sources[i]);
      const std::uint64_t bit = std::uint64_t(1) << i;
      if (!previous_[s]) frontier_.push_back(sources[i]);
      previous_[s] |= bit;
      visited_[s] |= bit;
      component_lanes_[static_cast<std::size_t>(component_[s])] |= bit;
      rows[static_cast<std::size_t>(i)].clear();
    }
    std::sort(frontier_.begin(), frontier_.end());
    // Level 0: one lane per source, N = 1 and S = M = 0.
    std::int32_t fresh_count = 0;
    for (std::size_t f = 0; f < frontier_.size(); ++f) {
      const std::int32_t s = frontier_[f];
      offset_previous_[static_cast<std::size_t>(s)] = static_cast<std::int32_t>(f);
      values_previous_.count[f] = 1.0;
      values_previous_.sum[f] = 0.0;
      if (!complete(s, visited_[static_cast<std::size_t>(s)])) set_live(s);
      fresh_[static_cast<std::size_t>(fresh_count++)] = s;
    }
    mark_unreached_neighbours(fresh_count);

    std::int64_t reached = lanes;
    double layer[64];
    double level_max_count[64];
    for (;;) {
      std::int32_t total = 0;
      std::uint64_t active_lanes = 0;
      sweep_level(total, active_lanes, fresh_count);
      if (next_frontier_.empty()) break;
      reached += total;
      mark_unreached_neighbours(fresh_count);

      // Delta of this level: per lane, the nodes in ascending order (positions ascend with the
      // node, and within a node with the lane).
      const std::uint8_t* lane_at = values_current_.lane.data();
      const double* sum = values_current_.sum.data();
      const double* count = values_current_.count.data();
      std::fill(layer, layer + 64, 0.0);
      if (Mode == TieMode::mean) {
        std::fill(level_max_count, level_max_count + 64, 0.0);
        for (std::int32_t k = 0; k < total; ++k) {
          const int i = lane_at[k];
          layer[i] += sum[k] / count[k];
          level_max_count[i] = std::max(level_max_count[i], count[k]);
        }
        rescale_large_counts(active_lanes, level_max_count);
      } else {
        for (std::int32_t k = 0; k < total; ++k) layer[lane_at[k]] += sum[k];
      }
      for (std::uint64_t m = active_lanes; m; m &= m - 1) {
        const int i = lowest_bit(m);
        rows[static_cast<std::size_t>(i)].push_back(layer[i]);
      }
      for (const std::int32_t p : frontier_) previous_[static_cast<std::size_t>(p)] = 0;
      previous_.swap(current_);
      frontier_.swap(next_frontier_);
      offset_previous_.swap(offset_current_);
      std::swap(values_previous_, values_current_);
    }
    for (const std::int32_t p : frontier_) previous_[static_cast<std::size_t>(p)] = 0;
    for (int i = 0; i < lanes; ++i) {
      component_lanes_[static_cast<std::size_t>(component_[static_cast<std::size_t>(sources[i])])] = 0;
    }
    return reached;
  }

 private:
  /// Compact values of one level: position k holds lane lane[k] of some node.
  struct LevelValues {
    std::vector<double> count;  // N (unused by TieMode::min)
    std::vector<double> sum;    // S, or M for TieMode::min
    std::vector<std::uint8_t> lane;
  };
  static constexpr std::size_t kInitialValues = 64 * 64;
  /// Slack after the last value: a node writes up to 16 values past its own and reads up to 16
  /// past a predecessor's; its lane list is written 64 bytes at a time.
  static constexpr std::size_t kPadding = 128;

  static void grow(LevelValues& v, std::size_t values) {
    const std::size_t size = values + kPadding;
    v.count.resize(size, 0.0);
    v.sum.resize(size, 0.0);
    v.lane.resize(size, 0);
  }

  void label_components(const Graph<Scalar>& g) {
    std::vector<std::int32_t> queue;
    for (std::int32_t s = 0; s < n_; ++s) {
      if (component_[static_cast<std::size_t>(s)] >= 0) continue;
      const std::int32_t c = static_cast<std::int32_t>(component_lanes_.size());
      component_lanes_.push_back(0);
      component_[static_cast<std::size_t>(s)] = c;
      queue.assign(1, s);
      for (std::size_t head = 0; head < queue.size(); ++head) {
        for (const std::int32_t w : g.neighbors(queue[head])) {
          if (component_[static_cast<std::size_t>(w)] < 0) {
            component_[static_cast<std::size_t>(w)] = c;
            queue.push_back(w);
          }
        }
      }
    }
  }

  /// A node is complete once every lane of its component has reached it.
  bool complete(std::int32_t u, std::uint64_t visited) const {
    return visited == component_lanes_[static_cast<std::size_t>(component_[static_cast<std::size_t>(u)])];
  }
  void set_live(std::int32_t u) { live_[static_cast<std::size_t>(u) >> 6] |= std::uint64_t(1) << (u & 63); }

  /// Unreached neighbours of the nodes reached for the first time become live: some lane reaches
  /// them at the next level. (A node reached earlier has no unreached neighbour left.)
  void mark_unreached_neighbours(std::int32_t fresh_count) {
    for (std::int32_t f = 0; f < fresh_count; ++f) {
      const std::int32_t u = fresh_[static_cast<std::size_t>(f)];
      for (std::int32_t e = offsets_[u], end = offsets_[u + 1]; e < end; ++e) {
        const std::int32_t w = adjacency_[e];
        live_[static_cast<std::size_t>(w) >> 6] |= std::uint64_t(visited_[static_cast<std::size_t>(w)] == 0)
                                                   << (w & 63);
      }
    }
  }

  /// TieMode::mean: scales the lanes_to_rescale of this level by mean_rescale_factor(), as
  /// BlockBfsDegreeSums does.
  void rescale_large_counts(std::uint64_t active_lanes, const double* level_max_count) {
    const std::uint64_t large = lanes_to_rescale(active_lanes, level_max_count);
    if (!large) return;
    const double factor = mean_rescale_factor();
    for (const std::int32_t u : next_frontier_) {
      std::int32_t k = offset_current_[static_cast<std::size_t>(u)];
      for (std::uint64_t m = current_[static_cast<std::size_t>(u)]; m; m &= m - 1, ++k) {
        if ((large >> lowest_bit(m)) & 1) {
          values_current_.count[static_cast<std::size_t>(k)] *= factor;
          values_current_.sum[static_cast<std::size_t>(k)] *= factor;
        }
      }
    }
  }

  /// One level: every live node in ascending order pulls from its neighbours on the previous
  /// level. Fills next_frontier_, current_, offset_current_ and values_current_; lists the nodes
  /// reached for the first time in fresh_.
  CGE_DEGREE_SUMS_AVX512_TARGET __attribute__((flatten)) void sweep_level(std::int32_t& total,
                                                                          std::uint64_t& active_lanes,
                                                                          std::int32_t& fresh_count) {
    next_frontier_.clear();
    fresh_count = 0;
    for (std::size_t w = 0; w < live_.size(); ++w) {
      for (std::uint64_t bits = live_[w]; bits; bits &= bits - 1) {
        const std::int32_t u = static_cast<std::int32_t>(w * 64 + static_cast<std::size_t>(lowest_bit(bits)));
        const std::size_t su = static_cast<std::size_t>(u);
        const std::uint64_t was = visited_[su];
        int preds = 0;
        const std::uint64_t here = pull(u, ~was, preds);
        if (!here) continue;  // not on this level (its lanes' sources straddle a gap)
        const int lanes_here = static_cast<int>(_mm_popcnt_u64(here));
        if (static_cast<std::size_t>(total + lanes_here) + kPadding > values_current_.sum.size()) {
          grow(values_current_, 2 * static_cast<std::size_t>(total + lanes_here));
        }
        accumulate(u, here, lanes_here, preds, total);
        offset_current_[su] = total;
        current_[su] = here;
        next_frontier_.push_back(u);
        total += lanes_here;
        active_lanes |= here;
        fresh_[static_cast<std::size_t>(fresh_count)] = u;
        fresh_count += was == 0;
        const std::uint64_t now = was | here;
        visited_[su] = now;
        live_[w] &= ~(std::uint64_t(complete(u, now)) << (u & 63));
      }
    }
  }

  /// The neighbours of u on the previous level, with the lanes for which each is a predecessor
  /// (ascending node order, no branch per neighbour). Returns the lanes that reach u now.
  CGE_DEGREE_SUMS_AVX512_TARGET std::uint64_t pull(std::int32_t u, std::uint64_t not_visited, int& preds) {
    const std::uint64_t* previous = previous_.data();
    std::uint64_t* mask = pred_mask_.data();
    std::int32_t* node = pred_node_.data();
    std::uint64_t here = 0;
    int c = 0;
    for (std::int32_t e = offsets_[u], end = offsets_[u + 1]; e < end; ++e) {
      const std::int32_t p = adjacency_[e];
      const std::uint64_t lanes = previous[p] & not_visited;
      here |= lanes;
      mask[c] = lanes;
      node[c] = p;
      c += lanes != 0;
    }
    preds = c;
    return here;
  }

  /// N and S (or M) of u's lanes `here`, written at position `at` of the current level, 8 or 16
  /// lanes at a time (one or two registers).
  CGE_DEGREE_SUMS_AVX512_TARGET void accumulate(std::int32_t u, std::uint64_t here, int lanes_here, int preds,
                                                std::int32_t at) {
    alignas(64) static constexpr std::uint8_t kLaneIds[64] = {
        0,  1,  2,  3,  4,  5,  6,  7,  8,  9,  10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21,
        22, 23, 24, 25, 26, 27, 28, 29, 30, 31, 32, 33, 34, 35, 36, 37, 38, 39, 40, 41, 42, 43,
        44, 45, 46, 47, 48, 49, 50, 51, 52, 53, 54, 55, 56, 57, 58, 59, 60, 61, 62, 63};
    _mm512_storeu_si512(values_current_.lane.data() + at,
                        _mm512_maskz_compress_epi8(here, _mm512_load_si512(kLaneIds)));
    if (lanes_here <= 8) {
      accumulate_window<1>(u, lanes_here, preds, at);
    } else {
      for (int q = 0; q < lanes_here; q += 16) accumulate_window<2>(u, lanes_here - q, preds, at + q);
    }
  }

  /// One window of `Chunks` registers of 8 lanes: the lanes at positions at.. of the current level.
  template <int Chunks>
  CGE_DEGREE_SUMS_AVX512_TARGET void accumulate_window(std::int32_t u, int left, int preds, std::int32_t at) {
    const std::uint8_t* lanes_of_u = values_current_.lane.data() + at;
    const double* count_previous = values_previous_.count.data();
    const double* sum_previous = values_previous_.sum.data();
    const __m512i one = _mm512_set1_epi64(1);
    const __m512i sixteen = _mm512_set1_epi64(16);
    const __m512d start = _mm512_set1_pd(Mode == TieMode::min ? std::numeric_limits<double>::infinity() : 0.0);
    const std::int32_t degree_u = degree_[static_cast<std::size_t>(u)];
    // Per register: which slots exist, their lane ids as bits, and the bits below them.
    __mmask8 exists[Chunks];
    __m512i bit[Chunks], below[Chunks];
    __m512d n[Chunks], s[Chunks];
    for (int c = 0; c < Chunks; ++c) {
      const int in_chunk = left - 8 * c;
      exists[c] = static_cast<__mmask8>(in_chunk >= 8 ? 0xffu : in_chunk > 0 ? (1u << in_chunk) - 1u : 0u);
      // (The zero-masked forms, because the plain ones trip GCC's -Wmaybe-uninitialized.)
      const __m512i id =
          _mm512_maskz_cvtepu8_epi64(0xff, _mm_loadl_epi64(reinterpret_cast<const __m128i*>(lanes_of_u + 8 * c)));
      bit[c] = _mm512_maskz_sllv_epi64(0xff, one, id);
      below[c] = _mm512_sub_epi64(bit[c], one);
      n[c] = _mm512_setzero_pd();
      s[c] = start;
    }
    for (int j = 0; j < preds; ++j) {
      const std::int32_t p = pred_node_[static_cast<std::size_t>(j)];
      const std::uint64_t lanes_of_p = previous_[static_cast<std::size_t>(p)];
      const __m512i p_lanes = _mm512_set1_epi64(static_cast<long long>(lanes_of_p));
      const __m512i via_p = _mm512_set1_epi64(static_cast<long long>(pred_mask_[static_cast<std::size_t>(j)]));
      const int degree_gap = degree_[static_cast<std::size_t>(p)] - degree_u;
      const __m512d diff = _mm512_set1_pd(static_cast<double>(degree_gap < 0 ? -degree_gap : degree_gap));
      // Slots whose lane has p as predecessor, and where p keeps that lane: its rank in p's mask.
      __mmask8 todo[Chunks];
      __m512i rank[Chunks];
      for (int c = 0; c < Chunks; ++c) {
        todo[c] = _mm512_mask_test_epi64_mask(exists[c], via_p, bit[c]);
        rank[c] = _mm512_popcnt_epi64(_mm512_and_si512(p_lanes, below[c]));
      }
      const std::size_t base = static_cast<std::size_t>(offset_previous_[static_cast<std::size_t>(p)]);
      const double* count_p = count_previous + base;
      const double* sum_p = sum_previous + base;
      const int lanes_p = static_cast<int>(_mm_popcnt_u64(lanes_of_p));
      for (int window = 0;; window += 16) {  // p's values 16 at a time (one window nearly always)
        const __m512d sum_lo = _mm512_loadu_pd(sum_p + window);
        const __m512d sum_hi = _mm512_loadu_pd(sum_p + window + 8);
        __m512d count_lo = _mm512_setzero_pd(), count_hi = _mm512_setzero_pd();
        if (Mode != TieMode::min) {
          count_lo = _mm512_loadu_pd(count_p + window);
          count_hi = _mm512_loadu_pd(count_p + window + 8);
        }
        __mmask8 k[Chunks];
        for (int c = 0; c < Chunks; ++c) {
          k[c] = _mm512_mask_cmplt_epu64_mask(todo[c], rank[c], sixteen);
          const __m512d sp = _mm512_permutex2var_pd(sum_lo, rank[c], sum_hi);
          if (Mode == TieMode::min) {
            // std::min(M_u, M_p + diff) keeps M_u unless the new value is smaller.
            s[c] = _mm512_mask_min_pd(s[c], k[c], _mm512_add_pd(sp, diff), s[c]);
          } else {
            const __m512d np = _mm512_permutex2var_pd(count_lo, rank[c], count_hi);
            __m512d t = _mm512_maskz_mul_pd(k[c], np, diff);
            // The product is rounded on its own, as in the portable kernel: no fused multiply-add.
            __asm__("" : "+v"(t));
            n[c] = _mm512_mask_add_pd(n[c], k[c], n[c], np);
            s[c] = _mm512_mask_add_pd(s[c], k[c], s[c], _mm512_maskz_add_pd(k[c], sp, t));
          }
        }
        if (window + 16 >= lanes_p) break;
        for (int c = 0; c < Chunks; ++c) {
          todo[c] = static_cast<__mmask8>(todo[c] & ~k[c]);
          rank[c] = _mm512_sub_epi64(rank[c], sixteen);
        }
      }
    }
    double* count_u = values_current_.count.data() + at;
    double* sum_u = values_current_.sum.data() + at;
    for (int c = 0; c < Chunks; ++c) {
      _mm512_storeu_pd(count_u + 8 * c, n[c]);
      _mm512_storeu_pd(sum_u + 8 * c, s[c]);
    }
  }

  std::int32_t n_;
  const std::int32_t* offsets_;
  const std::int32_t* adjacency_;
  std::vector<std::uint64_t> previous_, current_, visited_;  // one bit per lane
  std::vector<std::uint64_t> live_;                          // bitmap over nodes
  std::vector<std::int32_t> degree_;
  std::vector<std::int32_t> component_;                         // component id per node
  std::vector<std::uint64_t> component_lanes_;                  // lanes of this block in each component
  std::vector<std::int32_t> offset_previous_, offset_current_;  // a node's first position
  LevelValues values_previous_, values_current_;
  std::vector<std::uint64_t> pred_mask_;  // scratch of pull()
  std::vector<std::int32_t> pred_node_;
  std::vector<std::int32_t> fresh_;
  std::vector<std::int32_t> frontier_, next_frontier_;
};

}  // namespace detail
}  // namespace cge

#undef CGE_DEGREE_SUMS_AVX512_TARGET

#else  // no AVX-512 kernel on this platform

namespace cge {
namespace detail {
inline bool avx512_degree_sums_supported() { return false; }
}  // namespace detail
}  // namespace cge

#endif
