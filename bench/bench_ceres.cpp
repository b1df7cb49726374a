// The Ceres adapters on synthetic scenes of the pipeline's sizes: pose refinement of one frame (300
// and 1000 matched map points, 1 px noise scaled by the ORB octave, 10 % gross outliers, a start
// 0.05 rad / 5 cm off), pose-graph optimisation of 100 keyframes (sequential, covisibility and loop
// edges with noise, started from chained odometry), and global bundle adjustment of 30 keyframes x
// 1000 points (pixel + depth observations, 1 px / 1 cm noise, perturbed start), and the pipeline's
// local bundle adjustment with its own settings on a window of the real fr1/rpy slice's size (11
// free keyframes, 10 fixed observers, 1500 points, about 9000 observations, 5 % gross outliers).
// Each iteration solves from the same start; scene generation is outside the timed loop.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "cge/ceres.hpp"
#include "cge/slam/settings.hpp"

namespace {

double uniform(std::mt19937& rng, double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }

Eigen::Isometry3d random_motion(std::mt19937& rng, double angle_rad, double translation_m) {
  Eigen::Vector3d axis(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
  Eigen::Vector3d dir(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(angle_rad, axis.normalized()).toRotationMatrix();
  T.translation() = translation_m * dir.normalized();
  return T;
}

void BM_Ceres_PoseRefinement(benchmark::State& state) {
  std::mt19937 rng(1);
  const cge::PinholeIntrinsics<double> K;
  const Eigen::Isometry3d T_world_camera = random_motion(rng, 0.5, 1.0);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<cge::PoseObservation> observations;
  for (int i = 0; i < state.range(0); ++i) {
    cge::PoseObservation o;
    const Eigen::Vector2d px(uniform(rng, 0, 640), uniform(rng, 0, 480));
    o.point_world_m = T_world_camera * K.backproject(px.x(), px.y(), uniform(rng, 0.5, 5));
    o.sigma_px = std::pow(1.2, std::uniform_int_distribution<int>(0, 7)(rng));
    o.pixel_px = px + o.sigma_px * Eigen::Vector2d(noise(rng), noise(rng));
    if (i % 10 == 0) o.pixel_px += Eigen::Vector2d(uniform(rng, -60, 60), uniform(rng, -60, 60));
    if (state.range(2) == 1 && i % 2 == 0) {  // RGB-D tracking: a measured depth on half the points
      o.depth_m = (T_world_camera.inverse() * o.point_world_m).z() * (1 + 0.003 * noise(rng));
      o.sigma_depth_m = 0.003 * o.depth_m * o.depth_m;
    }
    observations.push_back(o);
  }
  const Eigen::Isometry3d start = T_world_camera * random_motion(rng, 0.05, 0.05);
  cge::PoseRefinementSettings settings;
  settings.backend = state.range(1) == 1 ? cge::PoseRefinementBackend::pose_lm : cge::PoseRefinementBackend::ceres;
  state.SetLabel(std::string(cge::pose_refinement_backend_name(settings.backend)) +
                 (state.range(2) == 1 ? ", half with depth" : ", pixels only"));
  const cge::PoseRefiner refiner(settings);
  int inliers = 0;
  for (auto _ : state) {
    const cge::PoseRefinementResult r = refiner.refine(K, observations, start);
    inliers = r.inlier_count;
    benchmark::DoNotOptimize(r.T_world_camera);
  }
  state.counters["inliers"] = inliers;
}
// Args: observations, backend (0 Ceres, 1 the own pose_lm), depth on half the points (0 no, 1 yes).
BENCHMARK(BM_Ceres_PoseRefinement)
    ->ArgsProduct({{300, 1000}, {0, 1}, {0, 1}})
    ->Unit(benchmark::kMillisecond);

void BM_Ceres_PoseGraph(benchmark::State& state) {
  std::mt19937 rng(2);
  const int n = static_cast<int>(state.range(0));
  std::vector<Eigen::Isometry3d> truth{Eigen::Isometry3d::Identity()};
  for (int i = 1; i < n; ++i) truth.push_back(truth.back() * random_motion(rng, 0.1, 0.2));
  std::vector<cge::PoseGraphEdge> edges;
  const auto add = [&](int a, int b) {
    const Eigen::Isometry3d m = truth[a].inverse() * truth[b] * random_motion(rng, 0.005, 0.01);
    edges.push_back(cge::PoseGraphEdge::weighted(a, b, m, 1e4, 1e2));
  };
  for (int i = 0; i + 1 < n; ++i) add(i, i + 1);        // sequential
  for (int i = 0; i + 2 < n; ++i) add(i, i + 2);        // covisibility
  for (int i = 0; i + 3 < n; i += 2) add(i, i + 3);     // covisibility
  for (int i = 0; i + 50 < n; i += 10) add(i, i + 50);  // loops
  std::vector<Eigen::Isometry3d> start{truth[0]};
  for (int i = 0; i + 1 < n; ++i) start.push_back(start.back() * edges[i].T_from_to);  // chained odometry
  const cge::PoseGraphOptimiser optimiser;
  int iterations = 0;
  for (auto _ : state) {
    const cge::PoseGraphResult r = optimiser.optimise(start, edges);
    iterations = r.iterations;
    benchmark::DoNotOptimize(r.T_world_camera);
  }
  state.counters["edges"] = static_cast<double>(edges.size());
  state.counters["iterations"] = iterations;
}
BENCHMARK(BM_Ceres_PoseGraph)->Arg(100)->Unit(benchmark::kMillisecond);

// How a synthetic keyframe observes the points in its view (pixel + depth, 1 cm depth noise).
struct ObservationModel {
  double matched_fraction = 1.0;  ///< of the points in view, the share observed, (0, 1]
  bool octave_sigma = false;      ///< pixel sigma 1.2^octave (octave uniform in 0..7), else 1 px
  double outlier_fraction = 0.0;  ///< observations moved by up to +-40 px, [0, 1)
};

// Every keyframe's observations of the points in front of it and inside the 640 x 480 image.
// Draws from `rng` only for the model's options in use, and takes the caller's `noise`, so a scene's
// later draws (its perturbed start) stay what they were.
std::vector<cge::BundleObservation> observe(const cge::PinholeIntrinsics<double>& K,
                                            const std::vector<Eigen::Isometry3d>& T_world_camera,
                                            const std::vector<Eigen::Vector3d>& points_world, const ObservationModel& model,
                                            std::mt19937& rng, std::normal_distribution<double>& noise) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<cge::BundleObservation> observations;
  for (int i = 0; i < static_cast<int>(T_world_camera.size()); ++i) {
    const Eigen::Isometry3d T_camera_world = T_world_camera[i].inverse();
    for (int j = 0; j < static_cast<int>(points_world.size()); ++j) {
      const Eigen::Vector3d p = T_camera_world * points_world[j];
      const Eigen::Vector2d px = K.project(p);
      if (p.z() <= 0 || px.x() < 0 || px.x() > 640 || px.y() < 0 || px.y() > 480) continue;
      if (model.matched_fraction < 1 && unit(rng) > model.matched_fraction) continue;
      cge::BundleObservation o;
      o.keyframe = i;
      o.point = j;
      if (model.octave_sigma) o.sigma_px = std::pow(1.2, std::uniform_int_distribution<int>(0, 7)(rng));
      o.pixel_px = px + o.sigma_px * Eigen::Vector2d(noise(rng), noise(rng));
      if (model.outlier_fraction > 0 && unit(rng) < model.outlier_fraction)
        o.pixel_px += Eigen::Vector2d(uniform(rng, -40, 40), uniform(rng, -40, 40));
      o.depth_m = p.z() + 0.01 * noise(rng);
      o.sigma_depth_m = 0.01;
      observations.push_back(o);
    }
  }
  return observations;
}

void BM_Ceres_BundleAdjustment(benchmark::State& state) {
  std::mt19937 rng(3);
  const int keyframes = static_cast<int>(state.range(0)), points = static_cast<int>(state.range(1));
  const cge::PinholeIntrinsics<double> K;
  std::vector<Eigen::Isometry3d> truth;
  for (int i = 0; i < keyframes; ++i) {
    Eigen::Isometry3d T = random_motion(rng, uniform(rng, 0, 0.08), 0.0);
    T.translation() = Eigen::Vector3d(0.3 * i, uniform(rng, -0.1, 0.1), uniform(rng, -0.1, 0.1));
    truth.push_back(T);
  }
  std::vector<Eigen::Vector3d> points_true;
  const double span = 0.3 * (keyframes - 1);
  for (int j = 0; j < points; ++j)
    points_true.emplace_back(uniform(rng, -2, span + 2), uniform(rng, -1.5, 1.5), uniform(rng, 3, 8));
  std::normal_distribution<double> noise(0.0, 1.0);
  const std::vector<cge::BundleObservation> observations = observe(K, truth, points_true, {}, rng, noise);
  std::vector<Eigen::Isometry3d> poses = truth;
  for (int i = 1; i < keyframes; ++i) poses[i] = truth[i] * random_motion(rng, 0.01, 0.03);
  std::vector<Eigen::Vector3d> points_start = points_true;
  for (Eigen::Vector3d& p : points_start) p += 0.05 * Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
  const cge::BundleAdjuster adjuster;
  cge::BundleAdjustmentResult r;
  for (auto _ : state) {
    r = adjuster.adjust(K, poses, points_start, observations);
    benchmark::DoNotOptimize(r.points_world_m);
  }
  state.counters["observations"] = static_cast<double>(observations.size());
  state.counters["iterations"] = r.iterations;
  state.counters["rms_px"] = r.final_rms_px;
}
BENCHMARK(BM_Ceres_BundleAdjustment)->Args({30, 1000})->Unit(benchmark::kMillisecond);

// The local BA as the pipeline runs it (slam::LocalMappingSettings' bundle settings: a Huber round
// and a plain round, dense Schur, their iteration cap), sized as on the real slice (docs/REAL_DATA.md):
// keyframes along a 0.6 m arc looking at a wall of points 1-4 m away, each point observed by the
// keyframes that see it (about six), pixel noise by the ORB octave, 1 cm depth noise. Third
// argument: the solver (0 Ceres, 1 cge's Schur-complement LM, BundleAdjustmentSettings::backend);
// the counter final_cost shows both reach the same optimum.
void BM_Ceres_LocalBundleAdjustment(benchmark::State& state) {
  std::mt19937 rng(4);
  const int free_keyframes = static_cast<int>(state.range(0)), fixed_keyframes = 10;
  const int keyframes = free_keyframes + fixed_keyframes, points = static_cast<int>(state.range(1));
  const cge::PinholeIntrinsics<double> K;
  std::vector<Eigen::Isometry3d> truth;
  for (int i = 0; i < keyframes; ++i) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::AngleAxisd(0.03 * (i - keyframes / 2), Eigen::Vector3d::UnitY()).toRotationMatrix();
    T.translation() = Eigen::Vector3d(0.03 * i, uniform(rng, -0.02, 0.02), uniform(rng, -0.02, 0.02));
    truth.push_back(T);
  }
  std::vector<Eigen::Vector3d> points_true;
  for (int j = 0; j < points; ++j) points_true.emplace_back(uniform(rng, -2, 2.6), uniform(rng, -1.5, 1.5), uniform(rng, 1, 4));
  std::normal_distribution<double> noise(0.0, 1.0);
  ObservationModel model;
  model.matched_fraction = 0.6;  // a keyframe matches 60 % of the points in its view
  model.octave_sigma = true;
  model.outlier_fraction = 0.05;
  const std::vector<cge::BundleObservation> observations = observe(K, truth, points_true, model, rng, noise);
  std::vector<int> fixed;
  for (int i = free_keyframes; i < keyframes; ++i) fixed.push_back(i);
  std::vector<Eigen::Isometry3d> poses = truth;
  for (int i = 0; i < free_keyframes; ++i) poses[i] = truth[i] * random_motion(rng, 0.003, 0.01);
  std::vector<Eigen::Vector3d> points_start = points_true;
  for (Eigen::Vector3d& p : points_start) p += 0.01 * Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
  cge::BundleAdjustmentSettings settings = cge::slam::LocalMappingSettings{}.bundle;
  settings.backend = state.range(2) == 1 ? cge::BundleAdjustmentBackend::schur_lm : cge::BundleAdjustmentBackend::ceres;
  state.SetLabel(state.range(2) == 1 ? "schur_lm" : "ceres");
  const cge::BundleAdjuster adjuster(settings);
  cge::BundleAdjustmentResult r;
  for (auto _ : state) {
    r = adjuster.adjust(K, poses, points_start, observations, fixed);
    benchmark::DoNotOptimize(r.points_world_m);
  }
  state.counters["observations"] = static_cast<double>(observations.size());
  state.counters["iterations"] = r.iterations;
  state.counters["rms_px"] = r.final_rms_px;
  state.counters["final_cost"] = r.final_cost;
}
BENCHMARK(BM_Ceres_LocalBundleAdjustment)->Args({11, 1500, 0})->Args({11, 1500, 1})->Unit(benchmark::kMillisecond);

}  // namespace
