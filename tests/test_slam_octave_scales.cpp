// OctaveScales (cge/slam/octave_scales.hpp): the oracle is std::pow itself. The table must return
// the very double std::pow gives, bit for bit, inside the table and beyond it, so that the matchers
// and the bundle-adjustment setup that look it up produce the same outputs as before.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>

#include "cge/slam/frame.hpp"
#include "cge/slam/octave_scales.hpp"

namespace {

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

}  // namespace

TEST_CASE("OctaveScales: the value of std::pow, bit for bit, in the table and past it", "[slam]") {
  const double scale_factor = GENERATE(1.2, 1.0, 2.0, 1.3333333333333333, 1.1892071150027210);
  const cge::slam::OctaveScales scales(scale_factor);
  CHECK(scales.scale_factor() == scale_factor);
  for (int octave = 0; octave < cge::slam::OctaveScales::kTableLevels + 8; ++octave) {
    INFO("scale factor " << scale_factor << ", octave " << octave);
    CHECK(same_bits(scales(octave), std::pow(scale_factor, octave)));
    cv::KeyPoint kp(10.f, 20.f, 31.f);
    kp.octave = octave;
    CHECK(same_bits(scales(octave), cge::slam::keypoint_sigma_px(kp, scale_factor)));
  }
}

TEST_CASE("OctaveScales: a keypoint without an octave counts as level 0", "[slam]") {
  const cge::slam::OctaveScales scales(1.2);
  CHECK(scales(-1) == 1.0);
  CHECK(scales(-7) == 1.0);
  CHECK(scales(0) == 1.0);
  CHECK(scales(1) == 1.2);
  CHECK(scales(2) == Approx(1.44).epsilon(1e-15));
}
