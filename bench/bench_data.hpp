#pragma once
// Deterministic inputs shared by the benchmarks (docs/BENCHMARK.md, "Data").
//
// Random numbers come from std::mt19937_64, whose output sequence the standard fixes, turned into
// doubles by hand (std::uniform_real_distribution and std::normal_distribution are
// implementation-defined), so the inputs are the same with every standard library. Normal
// deviates use Box-Muller through std::log / std::cos / std::sin, which may differ in the last ulp
// between C libraries; on one platform the inputs are bit-identical from run to run.

#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "cge/core/image_region.hpp"
#include "cge/core/mask.hpp"
#include "cge/core/semantic_instance.hpp"
#include "cge/graph/graph.hpp"
#include "cge/graph/graph_builder.hpp"
#include "cge/graph/neighbor_search.hpp"

namespace cge_bench {

using Point = Eigen::Vector2d;
using Points = std::vector<Point>;

constexpr double kPi = 3.14159265358979323846;
constexpr double kImageWidth = 640.0;   ///< px, TUM RGB-D
constexpr double kImageHeight = 480.0;  ///< px
/// Target mean degree of the random geometric graphs.
constexpr double kTargetMeanDegree = 6.0;

inline cge::ImageRegion<double> image_region() {
  cge::ImageRegion<double> image;
  image.width_px = kImageWidth;
  image.height_px = kImageHeight;
  return image;
}

/// Portable uniform and normal deviates on top of std::mt19937_64.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}

  /// Uniform in [0, 1), 53 random bits.
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Standard normal (Box-Muller, both deviates used).
  double normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    const double u1 = 1.0 - uniform();  // (0, 1]: log is finite
    const double u2 = uniform();
    const double r = std::sqrt(-2.0 * std::log(u1));
    spare_ = r * std::sin(2.0 * kPi * u2);
    has_spare_ = true;
    return r * std::cos(2.0 * kPi * u2);
  }

 private:
  std::mt19937_64 engine_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

// ---- random geometric graphs -----------------------------------------------------------------------

/// Base radius R (px) for n points uniform in the image so that the expected number of other
/// points within R, pi R^2 n / area, is kTargetMeanDegree (boundary effects ignored).
inline double rgg_radius_px(int n) {
  return std::sqrt(kTargetMeanDegree * kImageWidth * kImageHeight / (kPi * static_cast<double>(n)));
}

/// GraphBuilder settings for the random geometric graphs: every point is a node (no patch can be
/// dense) and R = rgg_radius_px(n), given as a fraction of the image diagonal. The measured mean
/// degree comes out at 8.3..8.8, not 6: a centre with nothing new within R searches again at 2R
/// (3R from round 3) and joins everything new there (docs/BENCHMARK.md, "Data").
inline cge::GraphBuilderSettings<double> rgg_settings(int n) {
  cge::GraphBuilderSettings<double> s;
  s.dense_patch_threshold = std::numeric_limits<int>::max();
  s.radius_fraction_of_diagonal = rgg_radius_px(n) / image_region().diagonal();
  return s;
}

/// n points uniform in [0, 640) x [0, 480); seed fixed per n.
inline const Points& rgg_points(int n) {
  static std::map<int, Points> cache;
  auto it = cache.find(n);
  if (it != cache.end()) return it->second;
  Rng rng(0xC6E5EED0ULL + static_cast<std::uint64_t>(n));
  Points pts;
  pts.reserve(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) pts.emplace_back(rng.uniform(0.0, kImageWidth), rng.uniform(0.0, kImageHeight));
  return cache.emplace(n, std::move(pts)).first->second;
}

/// The graph GraphBuilder makes of rgg_points(n) with rgg_settings(n), built once. As a guard on
/// the comparison of the two neighbour-search policies, the brute-force policy must give the
/// identical graph (throws otherwise).
inline const cge::Graph<double>& rgg_graph(int n) {
  static std::map<int, cge::Graph<double>> cache;
  auto it = cache.find(n);
  if (it != cache.end()) return it->second;
  const cge::GraphBuilder<double, cge::GridNeighborSearch<double>> grid(rgg_settings(n));
  const cge::GraphBuilder<double, cge::BruteForceNeighborSearch<double>> brute(rgg_settings(n));
  cge::Graph<double> g = grid.build(image_region(), rgg_points(n));
  if (g != brute.build(image_region(), rgg_points(n))) {
    throw std::logic_error("bench: grid and brute-force neighbour search built different graphs for n = " +
                           std::to_string(n));
  }
  return cache.emplace(n, std::move(g)).first->second;
}

/// The textbook random geometric graph of rgg_points(n): every pair within R = rgg_radius_px(n) is
/// joined, so the mean degree is about kTargetMeanDegree (a little less: points near the border
/// have fewer neighbours). Not connected in general; the entropy ignores unreachable pairs.
/// Built once by brute force; weights are the pixel lengths.
inline const cge::Graph<double>& disc_graph(int n) {
  static std::map<int, cge::Graph<double>> cache;
  auto it = cache.find(n);
  if (it != cache.end()) return it->second;
  const Points& pts = rgg_points(n);
  const double r = rgg_radius_px(n);
  std::vector<cge::Edge<double>> edges;
  for (int a = 0; a < n; ++a) {
    for (int b = a + 1; b < n; ++b) {
      const double d = (pts[static_cast<std::size_t>(a)] - pts[static_cast<std::size_t>(b)]).norm();
      if (d <= r) edges.push_back(cge::Edge<double>{a, b, d});
    }
  }
  cge::Graph<double> g = cge::Graph<double>::from_edges(n, std::move(edges), /*weighted=*/true, pts);
  return cache.emplace(n, std::move(g)).first->second;
}

/// Which graphs a benchmark runs on.
enum class GraphFamily {
  builder,  ///< what GraphBuilder makes of the points (mean degree 8.3 to 8.8)
  disc,     ///< the disc graph of the same points (mean degree about 6)
};

inline const cge::Graph<double>& family_graph(GraphFamily family, int n) {
  return family == GraphFamily::builder ? rgg_graph(n) : disc_graph(n);
}

inline double mean_degree(const cge::Graph<double>& g) {
  return g.num_nodes() > 0 ? 2.0 * g.num_edges() / g.num_nodes() : 0.0;
}

// ---- ORB-like frames -----------------------------------------------------------------------------

/// One frame's inputs for CGESimilarity.
struct Frame {
  Points keypoints;
  cge::BinaryMask dynamic_mask;
  std::vector<cge::SemanticInstance<double>> instances;
};

/// Axis-aligned box in pixels, [x0, x1) x [y0, y1).
struct Box {
  int x0, y0, x1, y1;
  Point centre() const { return Point(0.5 * (x0 + x1), 0.5 * (y0 + y1)); }
};

/// COCO class ids used for the semantic instances.
constexpr int kPerson = 0;
constexpr int kChair = 56;
constexpr int kTvMonitor = 62;

/// Keypoints distributed like ORB keypoints on a textured indoor image: most of them on a few
/// dozen texture blobs (Gaussian clusters of varying spread and weight), some uniform background,
/// and some on the person, which moves independently of the scene.
struct OrbScene {
  struct Cluster {
    Point centre;
    double sigma_px;
    double weight;
  };
  static constexpr int kSceneClusters = 36;
  static constexpr int kPersonClusters = 4;
  static constexpr double kBackgroundShare = 0.15;  ///< of the keypoints, uniform over the image
  static constexpr double kPersonShare = 0.10;      ///< of the keypoints, on the person

  std::vector<Cluster> scene;   ///< scene texture, image coordinates of frame 0
  std::vector<Cluster> person;  ///< relative to the person box's top-left corner

  explicit OrbScene(std::uint64_t seed) {
    Rng rng(seed);
    for (int i = 0; i < kSceneClusters; ++i) {
      // Spread 4..24 px; weights log-uniform over a factor e^3 ~ 20 (varying density).
      scene.push_back({Point(rng.uniform(20.0, kImageWidth - 20.0), rng.uniform(20.0, kImageHeight - 20.0)),
                       rng.uniform(4.0, 24.0), std::exp(3.0 * rng.uniform())});
    }
    for (int i = 0; i < kPersonClusters; ++i) {
      person.push_back({Point(rng.uniform(20.0, 100.0), rng.uniform(20.0, 300.0)), rng.uniform(6.0, 16.0), 1.0});
    }
  }

  /// n keypoints of the scene seen with the camera shifted by `shift` px, the person in `person_box`,
  /// and a dynamic mask covering that box. Static instances: a chair and a TV monitor.
  Frame frame(std::uint64_t seed, int n, const Point& shift, const Box& person_box) const {
    Rng rng(seed);
    Frame f;
    double total = 0.0;
    for (const Cluster& c : scene) total += c.weight;
    auto inside = [](const Point& p) {
      return p.x() >= 0 && p.y() >= 0 && p.x() < kImageWidth && p.y() < kImageHeight;
    };
    const Point person_origin(person_box.x0, person_box.y0);
    while (static_cast<int>(f.keypoints.size()) < n) {
      const double kind = rng.uniform();
      Point p;
      if (kind < kBackgroundShare) {
        p = Point(rng.uniform(0.0, kImageWidth), rng.uniform(0.0, kImageHeight));
      } else if (kind < kBackgroundShare + kPersonShare) {
        const Cluster& c = person[static_cast<std::size_t>(rng.uniform() * kPersonClusters)];
        p = person_origin + c.centre + c.sigma_px * Point(rng.normal(), rng.normal());
      } else {
        double pick = rng.uniform() * total;
        std::size_t k = 0;
        while (k + 1 < scene.size() && pick >= scene[k].weight) pick -= scene[k++].weight;
        const Cluster& c = scene[k];
        p = c.centre + shift + c.sigma_px * Point(rng.normal(), rng.normal());
      }
      if (inside(p)) f.keypoints.push_back(p);  // off-image draws are redrawn
    }
    f.dynamic_mask = cge::BinaryMask(static_cast<int>(kImageWidth), static_cast<int>(kImageHeight));
    for (int row = person_box.y0; row < person_box.y1; ++row) {
      for (int col = person_box.x0; col < person_box.x1; ++col) f.dynamic_mask.at(col, row) = 1;
    }
    cge::SemanticInstance<double> chair, tv, man;
    chair.centre_px = Point(150.0, 360.0) + shift;
    chair.class_id = kChair;
    tv.centre_px = Point(300.0, 140.0) + shift;
    tv.class_id = kTvMonitor;
    man.centre_px = person_box.centre();
    man.class_id = kPerson;
    man.dynamic = true;
    f.instances = {chair, tv, man};
    return f;
  }
};

/// Frames A and B: 1000 keypoints each, the camera moved by (12, -7) px between them, the person
/// walked 60 px to the left.
inline const Frame& orb_frame(int which) {
  static const OrbScene scene(0x0B5CE7EULL);
  static const Frame a = scene.frame(0xF0A11ULL, 1000, Point(0.0, 0.0), Box{420, 150, 540, 480});
  static const Frame b = scene.frame(0xF0B22ULL, 1000, Point(12.0, -7.0), Box{360, 150, 480, 480});
  return which == 0 ? a : b;
}

}  // namespace cge_bench
