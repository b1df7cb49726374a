#pragma once
// C++20 concepts mirroring the contracts written next to each traits struct and policy. They are
// checked only when the including code is compiled as C++20 (CGE_HAS_CONCEPTS is then 1); under
// C++17 this header defines nothing but CGE_HAS_CONCEPTS = 0, and the prose contracts are the
// reference.

#if defined(__cpp_concepts) && __cpp_concepts >= 201907L && __cplusplus >= 202002L
#define CGE_HAS_CONCEPTS 1
#else
#define CGE_HAS_CONCEPTS 0
#endif

#if CGE_HAS_CONCEPTS

#include <concepts>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "cge/core/mask.hpp"
#include "cge/core/point_traits.hpp"
#include "cge/core/depth_image.hpp"

namespace cge {

/// A point type adapted by cge::traits::Point2 (see point_traits.hpp).
template <typename P>
concept Point2Like = requires(const P& p) {
  { traits::Point2<P>::x(p) } -> std::convertible_to<double>;
  { traits::Point2<P>::y(p) } -> std::convertible_to<double>;
};

/// A mask type adapted by cge::traits::Mask (see mask.hpp).
template <typename M>
concept MaskLike = requires(const M& m, int col, int row) {
  { traits::Mask<M>::width(m) } -> std::convertible_to<int>;
  { traits::Mask<M>::height(m) } -> std::convertible_to<int>;
  { traits::Mask<M>::is_set(m, col, row) } -> std::convertible_to<bool>;
  { traits::Mask<M>::empty(m) } -> std::convertible_to<bool>;
};

/// A depth image type adapted by cge::traits::DepthImage (see cge/core/depth_image.hpp).
template <typename D>
concept DepthImageLike = requires(const D& d, int col, int row) {
  { traits::DepthImage<D>::width(d) } -> std::convertible_to<int>;
  { traits::DepthImage<D>::height(d) } -> std::convertible_to<int>;
  { traits::DepthImage<D>::depth_m(d, col, row) } -> std::convertible_to<double>;
};

/// A neighbour-search policy for GraphBuilder<Scalar, NS> (see neighbor_search.hpp).
template <typename NS, typename Scalar>
concept NeighborSearchPolicy = std::copy_constructible<NS> &&
    requires(NS ns, const NS& cns, const std::vector<Eigen::Matrix<Scalar, 2, 1>>& points, Scalar radius,
             std::int32_t query) {
  ns.build(points, radius);
  cns.for_each_within(query, radius, [](std::int32_t, Scalar) {});
};

/// A coefficient policy for DegreeDegreeEntropy: c_k from (k, diameter) (see coefficients.hpp).
template <typename C>
concept CoefficientPolicy = requires(const C& c, int k, int diameter) {
  { c(k, diameter) } -> std::convertible_to<double>;
};

/// An exponent-scaling policy for DegreeDegreeEntropy (see exponent_scaling.hpp).
template <typename X>
concept ExponentScalingPolicy = requires(const X& x, std::vector<double>& exponents) {
  x(exponents);
};

}  // namespace cge

#endif  // CGE_HAS_CONCEPTS
