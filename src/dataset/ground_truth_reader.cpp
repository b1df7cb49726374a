#include "ground_truth_reader.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "text_fields.hpp"

namespace cge {
namespace dataset {
namespace detail {

std::vector<GroundTruthPose> read_ground_truth(const std::filesystem::path& file, double quaternion_norm_tolerance) {
  constexpr std::size_t kFields = 8;
  std::ifstream in = open_text_file(file);
  std::vector<GroundTruthPose> poses;
  std::string text;
  double previous_s = 0;
  for (int line = 1; std::getline(in, text); ++line) {
    const std::vector<std::string_view> fields = split_fields(text);
    if (fields.empty() || fields[0][0] == '#') continue;
    const std::string where = file.string() + ":" + std::to_string(line);
    if (fields.size() != kFields) {
      throw std::invalid_argument(where + ": expected `timestamp tx ty tz qx qy qz qw`, got " +
                                  std::to_string(fields.size()) + " fields");
    }
    static const char* const kNames[kFields] = {"timestamp", "tx", "ty", "tz", "qx", "qy", "qz", "qw"};
    double v[kFields];
    for (std::size_t k = 0; k < kFields; ++k) v[k] = parse_real(fields[k], where, kNames[k]);
    // Equal timestamps occur in TUM's own files (fr2_desk: two poses at 1311868229.5760, written
    // with 4 decimals); both are kept. Decreasing ones are an error.
    if (!poses.empty() && v[0] < previous_s) {
      throw std::invalid_argument(where + ": timestamp " + std::string(fields[0]) +
                                  " comes before the previous line's; timestamps must not decrease");
    }
    Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);  // w, x, y, z
    const double norm = q.norm();
    if (!(std::abs(norm - 1.0) <= quaternion_norm_tolerance)) {
      throw std::invalid_argument(where + ": the quaternion has norm " + std::to_string(norm) + ", not 1 within " +
                                  std::to_string(quaternion_norm_tolerance));
    }
    q.coeffs() /= norm;
    GroundTruthPose p;
    p.timestamp_s = v[0];
    p.T_world_camera = Eigen::Isometry3d::Identity();
    p.T_world_camera.linear() = q.toRotationMatrix();
    p.T_world_camera.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
    poses.push_back(p);
    previous_s = v[0];
  }
  if (in.bad()) throw std::invalid_argument(file.string() + ": read error");
  return poses;
}

}  // namespace detail
}  // namespace dataset
}  // namespace cge
