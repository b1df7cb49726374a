#include "cge/mapping/map_image.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <opencv2/imgcodecs.hpp>

namespace cge {
namespace mapping {

namespace {

/// An axis-aligned square footprint on the floor with a height and a colour.
struct Splat {
  double x0, y0, x1, y1;  ///< world metres
  double top_z;
  Rgb8 colour;
};

void check(const MapImageSettings& s) {
  if (!(s.pixels_per_metre > 0 && std::isfinite(s.pixels_per_metre)))
    throw std::invalid_argument("MapImageSettings.pixels_per_metre must be finite and > 0");
  if (s.margin_px < 0) throw std::invalid_argument("MapImageSettings.margin_px must be >= 0");
  if (!(s.min_shade >= 0 && s.min_shade <= 1))
    throw std::invalid_argument("MapImageSettings.min_shade must be in [0, 1]");
  if (s.point_radius_px < 0) throw std::invalid_argument("MapImageSettings.point_radius_px must be >= 0");
  if (s.max_side_px < 1) throw std::invalid_argument("MapImageSettings.max_side_px must be >= 1");
}

cv::Mat rasterise(const std::vector<Splat>& splats, const MapImageSettings& s) {
  check(s);
  if (splats.empty()) return cv::Mat(2 * s.margin_px + 1, 2 * s.margin_px + 1, CV_8UC3, cv::Scalar(255, 255, 255));
  double x_min = splats[0].x0, x_max = splats[0].x1, y_min = splats[0].y0, y_max = splats[0].y1;
  double z_min = splats[0].top_z, z_max = splats[0].top_z;
  for (const Splat& p : splats) {
    x_min = std::min(x_min, p.x0);
    x_max = std::max(x_max, p.x1);
    y_min = std::min(y_min, p.y0);
    y_max = std::max(y_max, p.y1);
    z_min = std::min(z_min, p.top_z);
    z_max = std::max(z_max, p.top_z);
  }
  const double w = std::ceil((x_max - x_min) * s.pixels_per_metre) + 2 * s.margin_px + 1;
  const double h = std::ceil((y_max - y_min) * s.pixels_per_metre) + 2 * s.margin_px + 1;
  if (w > s.max_side_px || h > s.max_side_px) {
    throw std::invalid_argument("render_top_view: the image would be " + std::to_string(int(w)) + " x " +
                                std::to_string(int(h)) +
                                " pixels, more than max_side_px = " + std::to_string(s.max_side_px));
  }
  cv::Mat image(static_cast<int>(h), static_cast<int>(w), CV_8UC3, cv::Scalar(255, 255, 255));
  cv::Mat depth(image.size(), CV_64FC1, cv::Scalar(-std::numeric_limits<double>::infinity()));
  const auto col = [&](double x) {
    return static_cast<int>(std::floor((x - x_min) * s.pixels_per_metre)) + s.margin_px;
  };
  const auto row = [&](double y) {  // world y up in the image
    return static_cast<int>(h) - 1 - (static_cast<int>(std::floor((y - y_min) * s.pixels_per_metre)) + s.margin_px);
  };
  for (const Splat& p : splats) {
    const int c0 = std::max(0, col(p.x0)), c1 = std::min(image.cols - 1, std::max(col(p.x0), col(p.x1) - 1));
    const int r0 = std::max(0, std::min(row(p.y0), row(p.y1) + 1)), r1 = std::min(image.rows - 1, row(p.y0));
    const double shade = z_max > z_min ? s.min_shade + (1 - s.min_shade) * (p.top_z - z_min) / (z_max - z_min) : 1.0;
    const cv::Vec3b bgr(static_cast<std::uint8_t>(std::lround(p.colour.b * shade)),
                        static_cast<std::uint8_t>(std::lround(p.colour.g * shade)),
                        static_cast<std::uint8_t>(std::lround(p.colour.r * shade)));
    for (int r = r0; r <= r1; ++r) {
      for (int c = c0; c <= c1; ++c) {
        double& d = depth.at<double>(r, c);
        if (p.top_z > d) {  // strictly higher wins; equal heights keep the first drawn (input order)
          d = p.top_z;
          image.at<cv::Vec3b>(r, c) = bgr;
        }
      }
    }
  }
  return image;
}

}  // namespace

cv::Mat render_top_view(const OccupiedVoxels& map, const MapImageSettings& settings) {
  std::vector<Splat> splats;
  const double r = map.resolution_m;
  for (const MapVoxel& v : map.voxels) {
    const double top = (v.index.z() + 1) * r;
    if (top - r > settings.clip_above_m) continue;
    splats.push_back(
        Splat{v.index.x() * r, v.index.y() * r, (v.index.x() + 1) * r, (v.index.y() + 1) * r, top, v.colour});
  }
  return rasterise(splats, settings);
}

cv::Mat render_top_view(const std::vector<SemanticPoint>& cloud, const MapImageSettings& settings) {
  check(settings);
  std::vector<Splat> splats;
  const double half = (settings.point_radius_px + 0.5) / settings.pixels_per_metre;
  for (const SemanticPoint& p : cloud) {
    const double x = p.position_m.x(), y = p.position_m.y(), z = p.position_m.z();
    if (z > settings.clip_above_m) continue;
    splats.push_back(Splat{x - half, y - half, x + half, y + half, z, p.colour});
  }
  return rasterise(splats, settings);
}

void write_png(const std::filesystem::path& path, const cv::Mat& image, bool overwrite) {
  if (!overwrite && std::filesystem::exists(path)) {
    throw std::invalid_argument("write_png: " + path.string() + " exists (not overwritten)");
  }
  if (!cv::imwrite(path.string(), image)) throw std::runtime_error("write_png: cannot write " + path.string());
}

}  // namespace mapping
}  // namespace cge
