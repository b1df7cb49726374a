// Compiled as C++20 only: the concept mirrors of the contracts accept the types and policies the
// toolkit ships, reject types that break a contract, and the whole core compiles as C++20.
// The checks are static_asserts; running the program only confirms it was built.

#include <array>
#include <cstdio>
#include <utility>
#include <vector>

#include "cge/cge.hpp"

static_assert(CGE_HAS_CONCEPTS == 1, "this file must be compiled as C++20 with concepts");

namespace {

struct ForeignKeypoint {
  float u, v;
};
struct UnadaptedKeypoint {
  float u, v;
};
struct ForeignMask {
  int w = 0, h = 0;
};

struct CountingSearch {  // a policy with the right shape
  void build(const std::vector<Eigen::Vector2d>&, double) {}
  template <typename Visit>
  void for_each_within(std::int32_t, double, Visit&&) const {}
};
struct SearchWithoutBuild {
  template <typename Visit>
  void for_each_within(std::int32_t, double, Visit&&) const {}
};

struct HalfCoefficients {
  double operator()(int k, int diameter) const { return 0.5 * (diameter - k + 1); }
};
struct NotACallable {};
struct ClampScaling {
  void operator()(std::vector<double>& e) const {
    for (double& x : e) x = x > 1e3 ? 1e3 : x;
  }
};

}  // namespace

template <>
struct cge::traits::Point2<ForeignKeypoint> {
  static float x(const ForeignKeypoint& p) { return p.u; }
  static float y(const ForeignKeypoint& p) { return p.v; }
};
template <>
struct cge::traits::Mask<ForeignMask> {
  static int width(const ForeignMask& m) { return m.w; }
  static int height(const ForeignMask& m) { return m.h; }
  static bool is_set(const ForeignMask&, int, int) { return false; }
  static bool empty(const ForeignMask& m) { return m.w == 0; }
};

static_assert(cge::Point2Like<Eigen::Vector2d> && cge::Point2Like<Eigen::Vector2f>);
static_assert(cge::Point2Like<std::array<float, 2>> && cge::Point2Like<std::pair<double, double>>);
static_assert(cge::Point2Like<ForeignKeypoint>);
static_assert(!cge::Point2Like<UnadaptedKeypoint>);

static_assert(cge::MaskLike<cge::BinaryMask> && cge::MaskLike<cge::NoMask> && cge::MaskLike<ForeignMask>);
static_assert(!cge::MaskLike<UnadaptedKeypoint>);

static_assert(cge::DepthImageLike<cge::FloatDepthImage>);
static_assert(!cge::DepthImageLike<cge::BinaryMask> && !cge::DepthImageLike<UnadaptedKeypoint>);

static_assert(cge::NeighborSearchPolicy<cge::GridNeighborSearch<double>, double>);
static_assert(cge::NeighborSearchPolicy<cge::BruteForceNeighborSearch<float>, float>);
static_assert(cge::NeighborSearchPolicy<CountingSearch, double>);
static_assert(!cge::NeighborSearchPolicy<SearchWithoutBuild, double>);

static_assert(cge::CoefficientPolicy<cge::StandardCoefficients> && cge::CoefficientPolicy<HalfCoefficients>);
static_assert(cge::CoefficientPolicy<cge::CustomCoefficients<double (*)(int, int)>>);
static_assert(!cge::CoefficientPolicy<NotACallable>);
static_assert(cge::ExponentScalingPolicy<cge::ExponentScaling> && cge::ExponentScalingPolicy<ClampScaling>);
static_assert(!cge::ExponentScalingPolicy<HalfCoefficients>);

int main() {
  // The core also runs as C++20: a foreign keypoint and mask through the builder, custom policies
  // through the entropy.
  const std::vector<ForeignKeypoint> keypoints{{100, 100}, {140, 120}, {300, 200}, {320, 240}};
  const cge::GraphBuilder<double> builder;
  const cge::Graph<double> g = builder.build(cge::ImageRegion<double>{}, keypoints, ForeignMask{}, ForeignMask{}, {});
  const cge::DegreeDegreeEntropy<double, HalfCoefficients, ClampScaling> dde;
  const double index = dde.compute(g).information_index;
  std::printf("C++20 concepts: checks compiled; %d nodes, %d edges, I = %.6f\n", g.num_nodes(), g.num_edges(), index);
  return g.num_nodes() == 4 ? 0 : 1;
}
