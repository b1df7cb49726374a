// Example 3: DepthMADFilter on one RGB-D frame (docs/METHOD.md section 1).
//
// A segmentation network's mask rarely covers a person's outline: here it misses a 4-pixel rim.
// Step 1 drops the keypoints inside the mask; step 2 estimates the person's depth (mean d and mean
// absolute deviation MAD) from samples in the detection box whose disc of radius r lies inside the
// mask; step 3 drops the keypoints in the box whose depth lies within k * MAD of d: the rim. A
// keypoint in the box on the wall behind the person is kept, and so is one on the top of the head,
// which leans further from d than the MAD (the test's limit). The frame is synthesised (a wall at
// 3 m, a person at about 1.5 m), so the example needs no data set.

#include <cmath>
#include <cstdio>
#include <vector>

#include <Eigen/Core>

#include "cge/core/mask.hpp"
#include "cge/core/depth_image.hpp"
#include "cge/frontend/depth_mad_filter.hpp"
#include "cge/frontend/feature_label.hpp"
#include "cge/frontend/pixel_box.hpp"

int main() {
  const int width = 160, height = 120;
  // The person's silhouette: columns 60..99, rows 20..119 (to the bottom of the image).
  const int left = 60, right = 99, top = 20;
  cge::FloatDepthImage depth(width, height, 3.0f);  // metres; 0 or NaN would mean "no depth"
  for (int row = top; row < height; ++row) {
    for (int col = left; col <= right; ++col) depth.at(col, row) = 1.45f + 0.002f * static_cast<float>(row - top);
  }
  // The network's mask misses the outline: 4 pixels short on the left, right and top.
  cge::BinaryMask mask(width, height);
  for (int row = top + 4; row < height; ++row) {
    for (int col = left + 4; col <= right - 4; ++col) mask.at(col, row) = 1;
  }
  // The detector's box encloses the whole person, with some wall around it.
  const cge::PixelBox box = cge::PixelBox::from_corners(55, 15, 105, 120);
  const std::vector<cge::DynamicInstance<cge::BinaryMask>> people{cge::dynamic_instance(mask, box, 0)};

  struct Named {
    const char* what;
    Eigen::Vector2d pixel;
  };
  const std::vector<Named> keypoints{
      {"wall, far from the person", {20.0, 30.0}},  {"wall, right of the person", {140.0, 90.0}},
      {"chest (inside the mask)", {80.0, 50.0}},     {"hip (inside the mask)", {75.0, 80.0}},
      {"left rim of the person", {61.0, 60.0}},      {"right rim of the person", {98.0, 70.0}},
      {"top of the head (rim)", {80.0, 21.0}},       {"wall inside the box", {57.0, 40.0}},
  };
  std::vector<Eigen::Vector2d> pixels;
  for (const Named& k : keypoints) pixels.push_back(k.pixel);

  cge::DepthMADSettings settings;  // n = 100 samples, r = 6 px, k = 1 (docs/METHOD.md section 1)
  cge::DepthMADFilter<> filter(settings);
  filter.engine.seed(7);  // the box samples are random: seed per frame for reproducible labels
  const cge::DepthMADResult result = filter.filter(pixels, depth, people);

  const cge::InstanceDepthStats& person = result.instances[0];
  std::printf("person: %d of %d samples valid (%d off the mask), d = %.3f m, MAD = %.4f m, MAD test %s\n",
              person.valid_samples, person.samples_drawn, person.samples_off_mask, person.mean_depth_m, person.mad_m,
              person.mad_test_applied ? "applied" : "skipped");
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    const Eigen::Vector2d& p = keypoints[i].pixel;
    const double d = depth.at(static_cast<int>(p.x()), static_cast<int>(p.y()));
    const double gap = std::fabs(d - person.mean_depth_m), limit = settings.mad_scale * person.mad_m;
    const bool in_box =
        p.x() >= box.x_min_px && p.x() < box.x_max_px() && p.y() >= box.y_min_px && p.y() < box.y_max_px();
    char why[96];
    if (result.labels[i] == cge::FeatureLabel::dynamic_by_mask) {
      std::snprintf(why, sizeof why, "on the person's mask");
    } else if (in_box) {
      std::snprintf(why, sizeof why, "in the box, |depth - d| = %.3f m %s k MAD = %.3f m", gap,
                    gap < limit ? "<" : ">=", limit);
    } else {
      std::snprintf(why, sizeof why, "outside every mask and box");
    }
    std::printf("  (%5.1f, %5.1f) %-26s depth %.3f m  %-15s %s\n", p.x(), p.y(), keypoints[i].what, d,
                cge::to_string(result.labels[i]), why);
  }
  std::printf("eliminated %d of %zu keypoints: %d by mask, %d by MAD of depth; %d static\n", result.dynamic_count(),
              keypoints.size(), result.dynamic_by_mask_count, result.dynamic_by_mad_count, result.static_count);
  return 0;
}
