#pragma once
// The AVX-512 candidate scan of GridNeighborSearch, chosen at run time: 8 doubles or 16 floats per
// instruction instead of one, with the same arithmetic as within_radius (dx*dx + dy*dy <= r*r,
// each product rounded on its own, no fused multiply-add), so both scans report the same points
// with the same squared distances, in the same order.
// Compiled only for x86-64 with GCC or Clang, through target attributes (no flags needed by the
// including build).

#include <cstddef>
#include <cstdint>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define CGE_GRID_SCAN_HAVE_AVX512 1
#include <immintrin.h>
#else
#define CGE_GRID_SCAN_HAVE_AVX512 0
#endif

namespace cge {
namespace detail {

/// True when this CPU (and operating system) runs the AVX-512 scan.
inline bool avx512_grid_scan_supported() {
#if CGE_GRID_SCAN_HAVE_AVX512
  static const bool supported = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("popcnt");
  }();
  return supported;
#else
  return false;
#endif
}

/// Extra room the scan may write past the last hit (one full vector of hits).
constexpr std::size_t kGridScanPadding = 16;

#if CGE_GRID_SCAN_HAVE_AVX512

#define CGE_GRID_SCAN_AVX512_TARGET __attribute__((target("avx512f,popcnt")))

/// Writes, for the slot runs [begin[i], end[i]) (i < runs) of the cell-ordered arrays, the members
/// within the squared radius rr of (qx, qy) other than `query`, and their squared distances, in
/// slot order; returns their number.
CGE_GRID_SCAN_AVX512_TARGET inline std::size_t grid_scan_avx512(const double* xs, const double* ys,
                                                                const std::int32_t* members, const std::int32_t* begin,
                                                                const std::int32_t* end, int runs, double qx, double qy,
                                                                double rr, std::int32_t query, std::int32_t* hit_member,
                                                                double* hit_d2) {
  const __m512d vqx = _mm512_set1_pd(qx);
  const __m512d vqy = _mm512_set1_pd(qy);
  const __m512d vrr = _mm512_set1_pd(rr);
  const __m512i vquery = _mm512_set1_epi32(query);
  std::size_t hits = 0;
  for (int run = 0; run < runs; ++run)
    for (std::int32_t k = begin[run]; k < end[run]; k += 8) {
      const int left = end[run] - k;
      const __mmask8 in = static_cast<__mmask8>(left >= 8 ? 0xffu : (1u << left) - 1u);
      const __m512d dx = _mm512_sub_pd(vqx, _mm512_maskz_loadu_pd(in, xs + k));
      const __m512d dy = _mm512_sub_pd(vqy, _mm512_maskz_loadu_pd(in, ys + k));
      __m512d dx2 = _mm512_mul_pd(dx, dx);
      __m512d dy2 = _mm512_mul_pd(dy, dy);
      __asm__("" : "+v"(dx2), "+v"(dy2));  // round each product, as the scalar test does
      const __m512d d2 = _mm512_add_pd(dx2, dy2);
      const __m512i id = _mm512_maskz_loadu_epi32(static_cast<__mmask16>(in), members + k);
      const __mmask8 hit = static_cast<__mmask8>(_mm512_mask_cmp_pd_mask(in, d2, vrr, _CMP_LE_OQ) &
                                                 _mm512_mask_cmpneq_epi32_mask(static_cast<__mmask16>(in), id, vquery));
      _mm512_storeu_pd(hit_d2 + hits, _mm512_maskz_compress_pd(hit, d2));
      _mm512_storeu_si512(hit_member + hits, _mm512_maskz_compress_epi32(static_cast<__mmask16>(hit), id));
      hits += static_cast<std::size_t>(_mm_popcnt_u32(hit));
    }
  return hits;
}

/// The same for float coordinates, 16 per instruction.
CGE_GRID_SCAN_AVX512_TARGET inline std::size_t grid_scan_avx512(const float* xs, const float* ys,
                                                                const std::int32_t* members, const std::int32_t* begin,
                                                                const std::int32_t* end, int runs, float qx, float qy,
                                                                float rr, std::int32_t query, std::int32_t* hit_member,
                                                                float* hit_d2) {
  const __m512 vqx = _mm512_set1_ps(qx);
  const __m512 vqy = _mm512_set1_ps(qy);
  const __m512 vrr = _mm512_set1_ps(rr);
  const __m512i vquery = _mm512_set1_epi32(query);
  std::size_t hits = 0;
  for (int run = 0; run < runs; ++run)
    for (std::int32_t k = begin[run]; k < end[run]; k += 16) {
      const int left = end[run] - k;
      const __mmask16 in = static_cast<__mmask16>(left >= 16 ? 0xffffu : (1u << left) - 1u);
      const __m512 dx = _mm512_sub_ps(vqx, _mm512_maskz_loadu_ps(in, xs + k));
      const __m512 dy = _mm512_sub_ps(vqy, _mm512_maskz_loadu_ps(in, ys + k));
      __m512 dx2 = _mm512_mul_ps(dx, dx);
      __m512 dy2 = _mm512_mul_ps(dy, dy);
      __asm__("" : "+v"(dx2), "+v"(dy2));
      const __m512 d2 = _mm512_add_ps(dx2, dy2);
      const __m512i id = _mm512_maskz_loadu_epi32(in, members + k);
      const __mmask16 hit = static_cast<__mmask16>(_mm512_mask_cmp_ps_mask(in, d2, vrr, _CMP_LE_OQ) &
                                                   _mm512_mask_cmpneq_epi32_mask(in, id, vquery));
      _mm512_storeu_ps(hit_d2 + hits, _mm512_maskz_compress_ps(hit, d2));
      _mm512_storeu_si512(hit_member + hits, _mm512_maskz_compress_epi32(hit, id));
      hits += static_cast<std::size_t>(_mm_popcnt_u32(hit));
    }
  return hits;
}

#undef CGE_GRID_SCAN_AVX512_TARGET

#endif  // CGE_GRID_SCAN_HAVE_AVX512

}  // namespace detail
}  // namespace cge
