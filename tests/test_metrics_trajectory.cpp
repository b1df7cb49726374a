// Association, rigid alignment, ATE and RPE, each against an independent oracle written here:
// associate.py's all-pairs greedy literally, Horn's unit-quaternion alignment (the code under test
// uses the SVD), evaluate_rpe.py literally with 4x4 matrices and a linear closest-stamp search, and
// hand-worked trajectories whose errors are known in closed form. The real TUM files in
// /work/shared/data/tum_trajectories go through both the code and the oracles.

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <fstream>
#include <limits>
#include <numeric>
#include <random>
#include <set>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "cge/metrics/association.hpp"
#include "cge/metrics/ate.hpp"
#include "cge/metrics/rigid_alignment.hpp"
#include "cge/metrics/rpe.hpp"
#include "cge/metrics/tum_trajectory_io.hpp"
#include "test_support.hpp"

using namespace cge::metrics;

namespace {

const double kPi = std::acos(-1.0);

// ---- oracles ------------------------------------------------------------------------------------

/// associate.py literally: every pair, sort the (difference, a, b) tuples, greedy, sort by a.
std::vector<std::pair<double, double>> oracle_associate(const std::vector<double>& first,
                                                        const std::vector<double>& second, double offset,
                                                        double max_difference) {
  std::vector<std::tuple<double, double, double>> potential;
  for (const double a : first) {
    for (const double b : second) {
      if (std::abs(a - (b + offset)) < max_difference) potential.emplace_back(std::abs(a - (b + offset)), a, b);
    }
  }
  std::sort(potential.begin(), potential.end());
  std::set<double> first_keys(first.begin(), first.end()), second_keys(second.begin(), second.end());
  std::vector<std::pair<double, double>> matches;
  for (const auto& [diff, a, b] : potential) {
    (void)diff;
    if (first_keys.count(a) && second_keys.count(b)) {
      first_keys.erase(a);
      second_keys.erase(b);
      matches.emplace_back(a, b);
    }
  }
  std::sort(matches.begin(), matches.end());
  return matches;
}

std::vector<std::pair<double, double>> as_stamps(const std::vector<TimestampMatch>& matches,
                                                 const std::vector<double>& first, const std::vector<double>& second) {
  std::vector<std::pair<double, double>> out;
  for (const TimestampMatch& m : matches) out.emplace_back(first[m.first], second[m.second]);
  return out;
}

/// Horn (1987): the rotation is the unit quaternion of the largest eigenvalue of the 4x4 matrix N
/// built from the cross-covariance of the centred points; returns T with data ~ T model.
Eigen::Isometry3d oracle_horn(const std::vector<Eigen::Vector3d>& model, const std::vector<Eigen::Vector3d>& data) {
  Eigen::Vector3d cm = Eigen::Vector3d::Zero(), cd = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < model.size(); ++i) {
    cm += model[i];
    cd += data[i];
  }
  cm /= double(model.size());
  cd /= double(model.size());
  Eigen::Matrix3d M = Eigen::Matrix3d::Zero();  // sum m d^T
  for (std::size_t i = 0; i < model.size(); ++i) M += (model[i] - cm) * (data[i] - cd).transpose();
  const double Sxx = M(0, 0), Sxy = M(0, 1), Sxz = M(0, 2), Syx = M(1, 0), Syy = M(1, 1), Syz = M(1, 2), Szx = M(2, 0),
               Szy = M(2, 1), Szz = M(2, 2);
  Eigen::Matrix4d N;
  N << Sxx + Syy + Szz, Syz - Szy, Szx - Sxz, Sxy - Syx,  //
      Syz - Szy, Sxx - Syy - Szz, Sxy + Syx, Szx + Sxz,   //
      Szx - Sxz, Sxy + Syx, -Sxx + Syy - Szz, Syz + Szy,  //
      Sxy - Syx, Szx + Sxz, Syz + Szy, -Sxx - Syy + Szz;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eig(N);
  const Eigen::Vector4d q = eig.eigenvectors().col(3);  // eigenvalues ascending
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(q(0), q(1), q(2), q(3)).normalized().toRotationMatrix();
  T.translation() = cd - T.linear() * cm;
  return T;
}

struct Stats {
  double rmse, mean, median, std, min, max;
};

Stats oracle_stats(std::vector<double> v) {
  const double n = double(v.size());
  Stats s{};
  s.mean = std::accumulate(v.begin(), v.end(), 0.0) / n;
  s.rmse = std::sqrt(std::inner_product(v.begin(), v.end(), v.begin(), 0.0) / n);
  s.std = std::sqrt(s.rmse * s.rmse - s.mean * s.mean);  // E[x^2] - E[x]^2, a different route
  std::sort(v.begin(), v.end());
  s.min = v.front();
  s.max = v.back();
  s.median = v.size() % 2 ? v[v.size() / 2] : (v[v.size() / 2 - 1] + v[v.size() / 2]) / 2;
  return s;
}

struct OracleAte {
  std::size_t pairs;
  Stats stats;
};

OracleAte oracle_ate(const Trajectory& gt, const Trajectory& est, double max_difference = 0.02) {
  const std::vector<double> sg = timestamps(gt), se = timestamps(est);
  const auto matches = oracle_associate(sg, se, 0.0, max_difference);
  std::vector<Eigen::Vector3d> pg, pe;
  for (const auto& [a, b] : matches) {
    pg.push_back(gt[std::size_t(std::find(sg.begin(), sg.end(), a) - sg.begin())].T_world_camera.translation());
    pe.push_back(est[std::size_t(std::find(se.begin(), se.end(), b) - se.begin())].T_world_camera.translation());
  }
  const Eigen::Isometry3d T = oracle_horn(pe, pg);
  std::vector<double> e;
  for (std::size_t i = 0; i < pe.size(); ++i) e.push_back((T * pe[i] - pg[i]).norm());
  return {matches.size(), oracle_stats(e)};
}

std::size_t linear_closest(const std::vector<double>& L, double t) {
  std::size_t best = 0;
  for (std::size_t i = 1; i < L.size(); ++i) {
    if (std::abs(L[i] - t) < std::abs(L[best] - t)) best = i;
  }
  return best;
}

struct OracleRpe {
  std::size_t pairs;
  Stats trans;
  Stats rot_deg;
};

/// evaluate_rpe.py --fixed_delta literally (4x4 matrices, general inverses, linear closest search).
OracleRpe oracle_rpe(const Trajectory& gt, const Trajectory& est, double delta, bool frames) {
  const std::vector<double> sg = timestamps(gt), se = timestamps(est);
  std::vector<double> index(se.size());
  for (std::size_t i = 0; i < se.size(); ++i) index[i] = frames ? double(i) : se[i];
  std::vector<double> intervals;
  for (std::size_t k = 1; k < sg.size(); ++k) intervals.push_back(sg[k] - sg[k - 1]);
  const double max_gap = 2 * oracle_stats(intervals).median;
  auto ominus = [](const Eigen::Matrix4d& a, const Eigen::Matrix4d& b) -> Eigen::Matrix4d { return a.inverse() * b; };
  std::vector<double> trans, rot;
  for (std::size_t i = 0; i < se.size(); ++i) {
    const std::size_t j = linear_closest(index, index[i] + delta);
    if (j == se.size() - 1) continue;
    const std::size_t g0 = linear_closest(sg, se[i]), g1 = linear_closest(sg, se[j]);
    if (std::abs(sg[g0] - se[i]) > max_gap || std::abs(sg[g1] - se[j]) > max_gap) continue;
    const Eigen::Matrix4d error = ominus(ominus(est[j].T_world_camera.matrix(), est[i].T_world_camera.matrix()),
                                         ominus(gt[g1].T_world_camera.matrix(), gt[g0].T_world_camera.matrix()));
    trans.push_back(error.block<3, 1>(0, 3).norm());
    rot.push_back(std::acos(std::min(1.0, std::max(-1.0, (error.block<3, 3>(0, 0).trace() - 1) / 2))) * 180.0 / kPi);
  }
  return {trans.size(), oracle_stats(trans), oracle_stats(rot)};
}

// ---- helpers ------------------------------------------------------------------------------------

Eigen::Isometry3d random_pose(std::mt19937& rng, double translation_scale) {
  std::normal_distribution<double> n01(0.0, 1.0);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(n01(rng), n01(rng), n01(rng), n01(rng)).normalized().toRotationMatrix();
  T.translation() = translation_scale * Eigen::Vector3d(n01(rng), n01(rng), n01(rng));
  return T;
}

/// A smooth random camera path: n poses, period dt_s, from t0_s.
Trajectory random_path(std::mt19937& rng, std::size_t n, double t0_s, double dt_s) {
  std::uniform_real_distribution<double> phase(0.0, 2 * kPi);
  const double a = phase(rng), b = phase(rng), c = phase(rng);
  Trajectory t(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double s = double(i) * dt_s;
    t[i].timestamp_s = t0_s + s;
    t[i].T_world_camera.translation() =
        Eigen::Vector3d(std::sin(0.7 * s + a), std::cos(0.5 * s + b), 0.3 * std::sin(s + c));
    t[i].T_world_camera.linear() = (Eigen::AngleAxisd(0.4 * std::sin(0.3 * s + a), Eigen::Vector3d::UnitZ()) *
                                    Eigen::AngleAxisd(0.2 * std::cos(0.6 * s + b), Eigen::Vector3d::UnitX()))
                                       .toRotationMatrix();
  }
  return t;
}

void check_stats(const ErrorStatistics& s, const Stats& o, double tol) {
  CHECK(std::abs(s.rmse - o.rmse) <= tol);
  CHECK(std::abs(s.mean - o.mean) <= tol);
  CHECK(std::abs(s.median - o.median) <= tol);
  CHECK(std::abs(s.std - o.std) <= tol * 1e3);  // the oracle's E[x^2] - E[x]^2 route loses digits
  CHECK(std::abs(s.min - o.min) <= tol);
  CHECK(std::abs(s.max - o.max) <= tol);
}

std::string shared_file(const std::string& name) {
  return std::string(CGE_SHARED_DIR) + "/data/tum_trajectories/" + name;
}

bool shared_files_present(std::initializer_list<std::string> names) {
  for (const std::string& n : names) {
    if (!std::ifstream(shared_file(n))) return false;
  }
  return true;
}

Trajectory read_shared(const std::string& name) {
  TumReadSettings settings;
  settings.duplicate_timestamps = DuplicateTimestamps::keep_last;  // fr2_desk's ground truth repeats one stamp
  return read_tum_trajectory_file(shared_file(name), settings);
}

}  // namespace

// ---- association ----------------------------------------------------------------------------------

TEST_CASE("associate: hand-worked greedy choices", "[metrics]") {
  // 1.00 is 0.004 from 1.004 and 0.006 from 0.994; 1.01 is 0.006 from 1.004 and 0.016 from 0.994...
  const std::vector<double> first = {1.00, 1.01, 2.00, 3.00};
  const std::vector<double> second = {0.994, 1.004, 2.03, 2.995, 3.019};
  const auto m = associate(first, second);
  // Candidates by difference: (1.00,1.004) .004, (3.00,2.995) .005, (1.00,0.994) .006,
  // (1.01,1.004) .006, (1.01,0.994) .016, (3.00,3.019) .019; 2.00 has none (2.03 is 0.03 away).
  // Greedy: (1.00,1.004), (3.00,2.995), (1.01,0.994).
  REQUIRE(m.size() == 3);
  CHECK(m[0].first == 0);
  CHECK(m[0].second == 1);
  CHECK(m[1].first == 1);
  CHECK(m[1].second == 0);
  CHECK(m[2].first == 3);
  CHECK(m[2].second == 3);
  CHECK(as_stamps(m, first, second) == oracle_associate(first, second, 0.0, 0.02));
}

TEST_CASE("associate: the maximum difference is strict and the offset shifts the second list", "[metrics]") {
  const std::vector<double> first = {0.0, 1.0};
  const std::vector<double> second = {0.5, 1.5};
  AssociationSettings s;
  s.max_difference_s = 0.5;  // |0 - 0.5| = 0.5 is not < 0.5
  CHECK(associate(first, second, s).empty());
  s.max_difference_s = 0.5000001;
  CHECK(associate(first, second, s).size() == 2);
  s.max_difference_s = 0.02;
  s.offset_s = -0.5;
  const auto m = associate(first, second, s);
  REQUIRE(m.size() == 2);
  CHECK((m[0].first == 0 && m[0].second == 0 && m[1].first == 1 && m[1].second == 1));
}

TEST_CASE("associate: random lists agree with associate.py's all-pairs greedy", "[metrics]") {
  std::mt19937 rng(20250707);
  for (int trial = 0; trial < 300; ++trial) {
    std::uniform_int_distribution<int> count(0, 60);
    std::uniform_real_distribution<double> step(0.001, 0.05);
    std::uniform_real_distribution<double> start(-0.05, 0.05);
    auto make = [&](int n, double t0) {
      std::vector<double> v;
      double t = t0;
      for (int i = 0; i < n; ++i) {
        t += step(rng);
        v.push_back(std::round(t * 1e4) / 1e4);  // 4 decimals: ties in the difference do occur
      }
      v.erase(std::unique(v.begin(), v.end()), v.end());
      return v;
    };
    const std::vector<double> a = make(count(rng), start(rng)), b = make(count(rng), start(rng));
    AssociationSettings s;
    s.max_difference_s = std::uniform_real_distribution<double>(0.001, 0.05)(rng);
    s.offset_s = std::uniform_real_distribution<double>(-0.02, 0.02)(rng);
    INFO("trial " << trial);
    CHECK(as_stamps(associate(a, b, s), a, b) == oracle_associate(a, b, s.offset_s, s.max_difference_s));
  }
}

TEST_CASE("associate: bad settings and unsorted lists are refused", "[metrics]") {
  AssociationSettings s;
  s.max_difference_s = 0;
  CHECK_THAT(cge_test::invalid_argument_message([&] { associate(std::vector<double>{1}, std::vector<double>{1}, s); }),
             Catch::Contains("max_difference_s"));
  CHECK_THAT(cge_test::invalid_argument_message([&] {
               associate(std::vector<double>{2, 1}, std::vector<double>{1}, AssociationSettings{});
             }),
             Catch::Contains("first list: timestamp 1 does not come after"));
}

// ---- alignment ------------------------------------------------------------------------------------

TEST_CASE("align_rigid: recovers a known transform and agrees with Horn's quaternion method", "[metrics]") {
  std::mt19937 rng(7);
  std::normal_distribution<double> n01(0.0, 1.0);
  for (int trial = 0; trial < 100; ++trial) {
    const Eigen::Isometry3d T = random_pose(rng, 5.0);
    const std::size_t n = 3 + std::size_t(trial % 40);
    std::vector<Eigen::Vector3d> model, exact, noisy;
    for (std::size_t i = 0; i < n; ++i) {
      model.emplace_back(n01(rng), n01(rng), n01(rng));
      exact.push_back(T * model.back());
      noisy.push_back(exact.back() + 0.05 * Eigen::Vector3d(n01(rng), n01(rng), n01(rng)));
    }
    INFO("trial " << trial);
    const Eigen::Isometry3d A = align_rigid(model, exact);
    CHECK((A.matrix() - T.matrix()).cwiseAbs().maxCoeff() < 1e-9);
    const Eigen::Isometry3d B = align_rigid(model, noisy);
    const Eigen::Isometry3d H = oracle_horn(model, noisy);
    CHECK((B.matrix() - H.matrix()).cwiseAbs().maxCoeff() < 1e-9);
    CHECK(std::abs(B.linear().determinant() - 1.0) < 1e-12);
  }
}

TEST_CASE("align_rigid: a mirrored cloud still gets a rotation, as good as Horn's", "[metrics]") {
  // data = mirror(model): the best proper rotation is what both methods return (never det -1).
  std::mt19937 rng(11);
  std::normal_distribution<double> n01(0.0, 1.0);
  std::vector<Eigen::Vector3d> model, data;
  for (int i = 0; i < 20; ++i) {
    model.emplace_back(n01(rng), 2 * n01(rng), 3 * n01(rng));
    data.emplace_back(model.back().x(), model.back().y(), -model.back().z());
  }
  const Eigen::Isometry3d A = align_rigid(model, data), H = oracle_horn(model, data);
  CHECK(std::abs(A.linear().determinant() - 1.0) < 1e-12);
  double ea = 0, eh = 0;
  for (std::size_t i = 0; i < model.size(); ++i) {
    ea += (A * model[i] - data[i]).squaredNorm();
    eh += (H * model[i] - data[i]).squaredNorm();
  }
  CHECK(std::abs(ea - eh) < 1e-9 * (1 + eh));
}

TEST_CASE("align_rigid: degenerate inputs (one point, collinear points) and bad input", "[metrics]") {
  const std::vector<Eigen::Vector3d> one_m = {Eigen::Vector3d(1, 2, 3)}, one_d = {Eigen::Vector3d(-1, 0, 5)};
  CHECK((align_rigid(one_m, one_d) * one_m[0] - one_d[0]).norm() < 1e-12);
  // Collinear: any rotation about the line is optimal; the residuals are what matter.
  std::vector<Eigen::Vector3d> m, d;
  for (int i = 0; i < 5; ++i) {
    m.emplace_back(double(i), 0, 0);
    d.emplace_back(0, 2.0 * i, 1);  // a different spacing: residuals are not zero
  }
  const Eigen::Isometry3d A = align_rigid(m, d), H = oracle_horn(m, d);
  for (std::size_t i = 0; i < m.size(); ++i)
    CHECK(std::abs((A * m[i] - d[i]).norm() - (H * m[i] - d[i]).norm()) < 1e-9);
  CHECK_THAT(cge_test::invalid_argument_message([] { align_rigid({}, {}); }), Catch::Contains("no points"));
  CHECK_THAT(cge_test::invalid_argument_message([&] { align_rigid(m, one_d); }), Catch::Contains("differ in length"));
}

TEST_CASE("align_rigid over a subset: the fit of the copied pairs, bit for bit; bad subsets refused", "[metrics]") {
  std::mt19937 rng(19);
  std::normal_distribution<double> n01(0.0, 1.0);
  const Eigen::Isometry3d T = random_pose(rng, 3.0);
  std::vector<Eigen::Vector3d> model, data;
  for (int i = 0; i < 30; ++i) {
    model.emplace_back(n01(rng), n01(rng), n01(rng));
    data.push_back(T * model.back() + 0.02 * Eigen::Vector3d(n01(rng), n01(rng), n01(rng)));
  }
  const std::vector<std::vector<int>> subsets = {{4, 17, 9}, {0, 1, 2, 3, 29}, {28, 3, 11, 11, 6, 20, 14}};
  for (const std::vector<int>& subset : subsets) {
    std::vector<Eigen::Vector3d> m, d;
    for (const int i : subset) {
      m.push_back(model[static_cast<std::size_t>(i)]);
      d.push_back(data[static_cast<std::size_t>(i)]);
    }
    INFO("subset of " << subset.size());
    CHECK(align_rigid(model, data, subset.data(), subset.size()).matrix() == align_rigid(m, d).matrix());
  }
  const int out_of_range[] = {0, 30, 2};
  const int negative[] = {0, -1, 2};
  CHECK_THAT(cge_test::invalid_argument_message([&] { align_rigid(model, data, out_of_range, 3); }),
             Catch::Contains("outside"));
  CHECK_THAT(cge_test::invalid_argument_message([&] { align_rigid(model, data, negative, 3); }),
             Catch::Contains("outside"));
  CHECK_THAT(cge_test::invalid_argument_message([&] { align_rigid(model, data, negative, 0); }),
             Catch::Contains("no points"));
  std::vector<Eigen::Vector3d> shorter(data.begin(), data.end() - 1);
  CHECK_THAT(cge_test::invalid_argument_message([&] { align_rigid(model, shorter, subsets[0].data(), 3); }),
             Catch::Contains("differ in length"));
  std::vector<Eigen::Vector3d> with_nan = data;
  with_nan[17].x() = std::numeric_limits<double>::quiet_NaN();
  CHECK_THAT(cge_test::invalid_argument_message([&] { align_rigid(model, with_nan, subsets[0].data(), 3); }),
             Catch::Contains("not finite"));
}

// ---- ATE --------------------------------------------------------------------------------------------

TEST_CASE("ATE: an estimate that is a rigid copy of the ground truth has zero error", "[metrics]") {
  std::mt19937 rng(3);
  const Trajectory gt = random_path(rng, 200, 100.0, 1.0 / 30);
  const Eigen::Isometry3d T = random_pose(rng, 10.0);
  Trajectory est = gt;
  for (StampedPose& p : est) {
    p.T_world_camera = T * p.T_world_camera;
    p.timestamp_s += 0.004;  // within the 0.02 s association
  }
  const AteResult r = compute_ate(gt, est);
  CHECK(r.translation_m.count == 200);
  CHECK(r.translation_m.rmse < 1e-9);
  CHECK(r.translation_m.max < 1e-9);
  CHECK((r.T_groundtruth_estimate.matrix() - T.inverse().matrix()).cwiseAbs().maxCoeff() < 1e-9);
}

TEST_CASE("ATE: hand-worked residuals that the alignment cannot reduce", "[metrics]") {
  // Points +-x, +-y, +-z; each pair +-p is displaced by the same d_k with d_1 + d_2 + d_3 = 0. The
  // displacements neither move the centroid nor add cross-covariance, so the best alignment is
  // the identity and the errors are |d_k|: 0.03, 0.03, 0.04, 0.04, sqrt(0.0017) twice.
  const Eigen::Vector3d d1(0.01, 0.02, 0.02), d2(-0.04, 0, 0), d3 = -(d1 + d2);
  const std::vector<Eigen::Vector3d> points = {Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitX(),
                                               Eigen::Vector3d::UnitY(), -Eigen::Vector3d::UnitY(),
                                               Eigen::Vector3d::UnitZ(), -Eigen::Vector3d::UnitZ()};
  const std::vector<Eigen::Vector3d> d = {d1, d1, d2, d2, d3, d3};
  std::mt19937 rng(5);
  const Eigen::Isometry3d T = random_pose(rng, 3.0);  // the estimate lives in another world frame
  Trajectory gt(6), est(6);
  for (std::size_t i = 0; i < 6; ++i) {
    gt[i].timestamp_s = est[i].timestamp_s = double(i);
    gt[i].T_world_camera.translation() = points[i];
    est[i].T_world_camera.translation() = T * (points[i] + d[i]);
  }
  const AteResult r = compute_ate(gt, est);
  const double e3 = std::sqrt(0.0017);
  CHECK(r.translation_m.count == 6);
  CHECK(r.translation_m.rmse == Approx(std::sqrt((2 * 0.0009 + 2 * 0.0016 + 2 * 0.0017) / 6)).epsilon(1e-12));
  CHECK(r.translation_m.mean == Approx((0.03 + 0.04 + e3) / 3).epsilon(1e-12));
  CHECK(r.translation_m.median == Approx(0.04).epsilon(1e-12));
  CHECK(r.translation_m.min == Approx(0.03).epsilon(1e-12));
  CHECK(r.translation_m.max == Approx(e3).epsilon(1e-12));
  const double mean = (0.03 + 0.04 + e3) / 3;
  const double var = ((0.03 - mean) * (0.03 - mean) + (0.04 - mean) * (0.04 - mean) + (e3 - mean) * (e3 - mean)) / 3;
  CHECK(r.translation_m.std == Approx(std::sqrt(var)).epsilon(1e-9));
}

TEST_CASE("ATE: only associated poses count, and no association is an error", "[metrics]") {
  std::mt19937 rng(9);
  const Trajectory gt = random_path(rng, 100, 0.0, 0.01);  // 100 Hz ground truth
  Trajectory est;
  for (std::size_t i = 0; i < gt.size(); i += 3) est.push_back(gt[i]);  // 33 Hz estimate
  for (StampedPose& p : est) p.T_world_camera.translation() += Eigen::Vector3d(0.01, 0, 0);
  const AteResult r = compute_ate(gt, est);
  CHECK(r.matches.size() == est.size());
  CHECK(r.translation_m.rmse < 1e-9);  // a pure offset is aligned away
  const OracleAte o = oracle_ate(gt, est);
  CHECK(o.pairs == r.matches.size());
  Trajectory far = est;
  for (StampedPose& p : far) p.timestamp_s += 100;
  CHECK_THAT(cge_test::invalid_argument_message([&] { compute_ate(gt, far); }), Catch::Contains("ATE: no timestamp"));
}

TEST_CASE("ATE: random noisy estimates agree with the oracle (brute-force association, Horn)", "[metrics]") {
  std::mt19937 rng(13);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::uniform_real_distribution<double> jitter(-0.015, 0.015);
  for (int trial = 0; trial < 20; ++trial) {
    const Trajectory gt = random_path(rng, 300, 50.0, 0.01);
    const Eigen::Isometry3d T = random_pose(rng, 2.0);
    Trajectory est;
    for (std::size_t i = 0; i < gt.size(); i += 3) {
      StampedPose p = gt[i];
      p.timestamp_s += jitter(rng);
      if (!est.empty() && p.timestamp_s <= est.back().timestamp_s) continue;
      p.T_world_camera.translation() += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
      p.T_world_camera = T * p.T_world_camera;
      est.push_back(p);
    }
    const AteResult r = compute_ate(gt, est);
    const OracleAte o = oracle_ate(gt, est);
    INFO("trial " << trial);
    CHECK(r.translation_m.count == o.pairs);
    check_stats(r.translation_m, o.stats, 1e-10);
  }
}

// ---- RPE --------------------------------------------------------------------------------------------

TEST_CASE("RPE: tum_closest_index is a closest index, with the tool's tie rule", "[metrics]") {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(0.0, 100.0);
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<double> L(1 + std::size_t(trial % 50));
    for (double& x : L) x = u(rng);
    std::sort(L.begin(), L.end());
    const double t = u(rng) * 1.2 - 10;
    const std::size_t i = detail::tum_closest_index(L, t);
    CHECK(std::abs(L[i] - t) == std::abs(L[linear_closest(L, t)] - t));
  }
  // Hand-worked tie: search 1.5 in {0,1,2,3} visits index 2 (distance 0.5) before index 1 (also 0.5).
  CHECK(detail::tum_closest_index({0, 1, 2, 3}, 1.5) == 2);
  // Search 0.5 in {0,1,2,3}: the search starts with index 0 as best (0.5); 2 (1.5) and 1 (0.5) are
  // not strictly closer: 0.
  CHECK(detail::tum_closest_index({0, 1, 2, 3}, 0.5) == 0);
  CHECK(detail::tum_closest_index({0, 1, 2, 3}, 2.0) == 2);
  CHECK(detail::tum_closest_index({0, 1, 2, 3}, 99.0) == 3);
}

TEST_CASE("RPE: an estimate that is a rigid copy of the ground truth has zero error", "[metrics]") {
  std::mt19937 rng(19);
  const Trajectory gt = random_path(rng, 150, 10.0, 1.0 / 30);
  const Eigen::Isometry3d T = random_pose(rng, 4.0);
  Trajectory est = gt;
  for (StampedPose& p : est) p.T_world_camera = T * p.T_world_camera;
  const RpeResult r = compute_rpe(gt, est);
  CHECK(r.translation_m.max < 1e-9);
  CHECK(r.rotation_deg.max < 1e-4);  // acos near 1 resolves about 1e-8 rad
}

TEST_CASE("RPE: hand-worked drift in translation, 1 s and 10 frames", "[metrics]") {
  // Ground truth moves along x at 1 m/s, 10 Hz, 101 poses (t = 0 .. 10 s); the estimate moves at
  // 1.1 m/s. Every pair 1 s (10 poses) apart is off by 0.1 m; pairs i = 0 .. 89 are kept (for
  // i >= 90 the partner is the last pose, which the tool drops): 90 pairs.
  Trajectory gt(101), est(101);
  for (std::size_t i = 0; i < 101; ++i) {
    gt[i].timestamp_s = est[i].timestamp_s = 0.1 * double(i);
    gt[i].T_world_camera.translation() = Eigen::Vector3d(0.1 * double(i), 0, 0);
    est[i].T_world_camera.translation() = Eigen::Vector3d(0.11 * double(i), 0, 0);
  }
  const RpeResult r = compute_rpe(gt, est);
  CHECK(r.pairs.size() == 90);
  CHECK(r.translation_m.rmse == Approx(0.1).epsilon(1e-9));
  CHECK(r.translation_m.min == Approx(0.1).epsilon(1e-9));
  CHECK(r.translation_m.max == Approx(0.1).epsilon(1e-9));
  CHECK(r.rotation_deg.max == 0.0);
  RpeSettings frames;
  frames.delta = 10;
  frames.delta_unit = RpeDeltaUnit::frames;
  const RpeResult f = compute_rpe(gt, est, frames);
  CHECK(f.pairs.size() == 90);
  CHECK(f.translation_m.mean == Approx(0.1).epsilon(1e-9));
  frames.delta = 1;
  const RpeResult f1 = compute_rpe(gt, est, frames);
  CHECK(f1.pairs.size() == 99);  // i = 0 .. 98; i = 99 pairs with the last pose
  CHECK(f1.translation_m.mean == Approx(0.01).epsilon(1e-9));
}

TEST_CASE("RPE: hand-worked drift in rotation", "[metrics]") {
  // The ground truth stands still; the estimate turns about z at 2 deg/s, sampled at 5 Hz for 4 s.
  // Over 1 s the relative rotation is 2 degrees, the translation 0.
  Trajectory gt(21), est(21);
  for (std::size_t i = 0; i < 21; ++i) {
    gt[i].timestamp_s = est[i].timestamp_s = 0.2 * double(i);
    est[i].T_world_camera.linear() =
        Eigen::AngleAxisd(2.0 * 0.2 * double(i) * kPi / 180, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  }
  const RpeResult r = compute_rpe(gt, est);
  CHECK(r.pairs.size() == 15);  // i = 0 .. 14; i = 15 pairs with the last pose (t = 4 s)
  CHECK(r.rotation_deg.rmse == Approx(2.0).epsilon(1e-7));
  CHECK(r.rotation_deg.min == Approx(2.0).epsilon(1e-7));
  CHECK(r.translation_m.max < 1e-12);
}

TEST_CASE("RPE: pairs whose ground truth is too far in time are skipped", "[metrics]") {
  // Ground truth at 10 Hz with a 1 s hole between 3 s and 4 s (median interval 0.1 s, limit 0.2 s).
  Trajectory gt, est;
  for (int i = 0; i <= 80; ++i) {
    const double t = 0.1 * i;
    StampedPose p;
    p.timestamp_s = t;
    p.T_world_camera.translation() = Eigen::Vector3d(t, 0, 0);
    est.push_back(p);
    if (!(t > 3.05 && t < 3.95)) gt.push_back(p);
  }
  const RpeResult r = compute_rpe(gt, est);
  const OracleRpe o = oracle_rpe(gt, est, 1.0, false);
  CHECK(r.pairs.size() == o.pairs);
  CHECK(r.pairs.size() < 70);  // 70 pairs without the hole
  for (const RpePair& p : r.pairs) {
    CHECK(std::abs(gt[p.groundtruth_first].timestamp_s - est[p.estimate_first].timestamp_s) <= 0.2);
    CHECK(std::abs(gt[p.groundtruth_second].timestamp_s - est[p.estimate_second].timestamp_s) <= 0.2);
  }
}

TEST_CASE("RPE: random noisy estimates agree with the literal oracle", "[metrics]") {
  std::mt19937 rng(23);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::uniform_real_distribution<double> jitter(-0.004, 0.004);
  for (int trial = 0; trial < 10; ++trial) {
    const Trajectory gt = random_path(rng, 600, 20.0, 0.01);
    Trajectory est;
    for (std::size_t i = 0; i < gt.size(); i += 3) {
      StampedPose p = gt[i];
      p.timestamp_s += jitter(rng);
      p.T_world_camera.translation() += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
      p.T_world_camera.linear() =
          p.T_world_camera.linear() *
          Eigen::AngleAxisd(noise(rng), Eigen::Vector3d(noise(rng), 1, noise(rng)).normalized()).toRotationMatrix();
      est.push_back(p);
    }
    INFO("trial " << trial);
    const RpeResult r = compute_rpe(gt, est);
    const OracleRpe o = oracle_rpe(gt, est, 1.0, false);
    CHECK(r.pairs.size() == o.pairs);
    check_stats(r.translation_m, o.trans, 1e-10);
    check_stats(r.rotation_deg, o.rot_deg, 1e-6);
    RpeSettings frames;
    frames.delta = 5;
    frames.delta_unit = RpeDeltaUnit::frames;
    const RpeResult f = compute_rpe(gt, est, frames);
    const OracleRpe of = oracle_rpe(gt, est, 5.0, true);
    CHECK(f.pairs.size() == of.pairs);
    check_stats(f.translation_m, of.trans, 1e-10);
  }
}

TEST_CASE("RPE: bad settings and too little data are refused", "[metrics]") {
  std::mt19937 rng(29);
  const Trajectory gt = random_path(rng, 50, 0.0, 0.1);
  RpeSettings s;
  s.delta = 0;
  CHECK_THAT(cge_test::invalid_argument_message([&] { compute_rpe(gt, gt, s); }), Catch::Contains("delta must be"));
  s.delta = 1.5;
  s.delta_unit = RpeDeltaUnit::frames;
  CHECK_THAT(cge_test::invalid_argument_message([&] { compute_rpe(gt, gt, s); }), Catch::Contains("whole number"));
  const Trajectory one(gt.begin(), gt.begin() + 1);
  CHECK_THAT(cge_test::invalid_argument_message([&] { compute_rpe(gt, one); }), Catch::Contains("at least two poses"));
  const Trajectory short_est(gt.begin(), gt.begin() + 5);  // 0.4 s long: no pair 1 s apart
  CHECK_THAT(cge_test::invalid_argument_message([&] { compute_rpe(gt, short_est); }),
             Catch::Contains("fewer than two pose pairs"));
  Trajectory late = gt;
  for (StampedPose& p : late) p.timestamp_s += 1000;  // every estimate maps to the last gt stamp
  CHECK_THAT(cge_test::invalid_argument_message([&] { compute_rpe(gt, late); }), Catch::Contains("hardly overlap"));
}

// ---- the real TUM files -------------------------------------------------------------------------------

TEST_CASE("ATE and RPE on the real TUM trajectories agree with the oracles (skipped without the shared data)",
          "[metrics][shared]") {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"freiburg1_xyz-groundtruth.txt", "freiburg1_xyz-rgbdslam.txt"},
      {"freiburg1_xyz-groundtruth.txt", "freiburg1_xyz-rgbdslam_drift.txt"},
      {"fr2_desk_groundtruth.txt", "fr2_desk_ORB.txt"}};
  for (const auto& [gt_name, est_name] : cases) {
    if (!shared_files_present({gt_name, est_name})) {
      WARN("skipped: " << shared_file(est_name) << " or its ground truth is absent");
      continue;
    }
    INFO(est_name);
    const Trajectory gt = read_shared(gt_name);
    const Trajectory est = read_shared(est_name);
    const AteResult ate = compute_ate(gt, est);
    const OracleAte oate = oracle_ate(gt, est);
    CHECK(ate.translation_m.count == oate.pairs);
    check_stats(ate.translation_m, oate.stats, 1e-10);
    const RpeResult rpe = compute_rpe(gt, est);
    const OracleRpe orpe = oracle_rpe(gt, est, 1.0, false);
    CHECK(rpe.pairs.size() == orpe.pairs);
    check_stats(rpe.translation_m, orpe.trans, 1e-10);
    check_stats(rpe.rotation_deg, orpe.rot_deg, 1e-6);
    RpeSettings frames;
    frames.delta_unit = RpeDeltaUnit::frames;
    const RpeResult rpe_f = compute_rpe(gt, est, frames);
    const OracleRpe orpe_f = oracle_rpe(gt, est, 1.0, true);
    CHECK(rpe_f.pairs.size() == orpe_f.pairs);
    check_stats(rpe_f.translation_m, orpe_f.trans, 1e-10);
    // Plausibility: RGB-D SLAM on these sequences is good to a few centimetres.
    CHECK(ate.translation_m.rmse > 0.001);
    CHECK(ate.translation_m.rmse < 0.05);
  }
}

TEST_CASE("TUM reader: the fr2_desk ground truth repeats one stamp (skipped without the shared data)",
          "[metrics][shared]") {
  const std::string path = shared_file("fr2_desk_groundtruth.txt");
  if (!std::ifstream(path)) {
    WARN("skipped: " << path << " is absent");
    return;
  }
  CHECK_THAT(
      cge_test::invalid_argument_message([&] { read_tum_trajectory_file(path); }),
      Catch::Contains("fr2_desk_groundtruth.txt:10863: timestamp 1311868229.5760 repeats the one on line 10862"));
  TumReadSettings settings;
  settings.duplicate_timestamps = DuplicateTimestamps::keep_last;
  TumReadReport report;
  const Trajectory t = read_tum_trajectory_file(path, settings, &report);
  CHECK(report.replaced_lines == std::vector<std::size_t>{10862});
  CHECK(t.size() == 20956);  // 20960 lines - 3 comments - 1 replaced
}
