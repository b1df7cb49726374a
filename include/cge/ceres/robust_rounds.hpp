#pragma once
// RobustRoundsSettings: the round schedule and chi2 outlier test that the pose refiner and the bundle
// adjuster share, as ORB-SLAM2's g2o optimisations do: a few optimise / re-classify rounds, the
// first ones with a Huber loss on the whitened residual, each later one on the previous round's
// inliers; an observation is an outlier when its chi2 exceeds the 95 % quantile for its degrees of
// freedom (2: pixel only, 3: pixel + depth) or its point is not in front of the camera.
// The two optimisers differ only in the default schedule (PoseRefinementSettings: 4 rounds, 2
// robust; BundleAdjustmentSettings: 2 rounds, 1 robust), which their constructors set.
#include <cmath>
#include <stdexcept>
#include <string>

namespace cge {

struct RobustRoundsSettings {
  /// Optimise / re-classify rounds, >= 1 (defaults: the deriving settings).
  int rounds = 1;
  /// The first this many rounds use the Huber loss, the rest none, 0..rounds.
  int robust_rounds = 0;
  /// Huber width on the whitened residual norm, sigma units (ORB-SLAM2: sqrt(5.991)); 0 = no robust
  /// loss in any round, >= 0.
  double huber_delta = 2.4477;
  /// Pixel-only observation: outlier when its chi2 (2 dof) exceeds this (95 %: 5.991), > 0.
  double chi2_threshold_2dof = 5.991;
  /// Pixel + depth observation: outlier when its chi2 (3 dof) exceeds this (95 %: 7.815), > 0.
  double chi2_threshold_3dof = 7.815;
  /// A point at or closer than this depth in a camera frame is an outlier there, metres, >= 0.
  double min_depth_m = 1e-6;

  /// True when round `round` (0-based) uses the Huber loss.
  bool robust_in_round(int round) const { return round < robust_rounds && huber_delta > 0; }

  /// The chi2 threshold for an observation with (3 dof) or without (2 dof) a measured depth.
  double chi2_threshold(bool with_depth) const { return with_depth ? chi2_threshold_3dof : chi2_threshold_2dof; }

  /// Throws std::invalid_argument naming the bad field, prefixed by `owner` (the deriving settings).
  void validate_rounds(const std::string& owner) const {
    const auto fail = [&](const std::string& what) { throw std::invalid_argument(owner + ": " + what); };
    if (rounds < 1) fail("rounds must be at least 1");
    if (robust_rounds < 0 || robust_rounds > rounds) fail("robust_rounds must be in [0, rounds]");
    if (!(std::isfinite(huber_delta) && huber_delta >= 0)) fail("huber_delta must be finite and not negative");
    if (!(std::isfinite(chi2_threshold_2dof) && chi2_threshold_2dof > 0))
      fail("chi2_threshold_2dof must be finite and positive");
    if (!(std::isfinite(chi2_threshold_3dof) && chi2_threshold_3dof > 0))
      fail("chi2_threshold_3dof must be finite and positive");
    if (!(std::isfinite(min_depth_m) && min_depth_m >= 0)) fail("min_depth_m must be finite and not negative");
  }
};

}  // namespace cge
