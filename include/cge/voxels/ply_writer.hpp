#pragma once
// Binary little-endian PLY of a semantic cloud, readable by MeshLab, CloudCompare and Open3D:
//
//   ply / format binary_little_endian 1.0 / comment <comment> / element vertex N
//   property float x / property float y / property float z          (world, metres)
//   property uchar red / property uchar green / property uchar blue
//   property ushort label                                             (COCO class id + 1, 0 = none)
//   end_header, then N records of 17 bytes.
//
// Never overwrites an existing file unless `overwrite` is set.

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "cge/voxels/semantic_point.hpp"

namespace cge {
namespace mapping {

namespace detail {
/// Appends an unsigned integer of N bytes, least significant byte first.
template <typename UInt>
void put_little_endian(std::string& out, UInt value) {
  for (std::size_t i = 0; i < sizeof(UInt); ++i) out.push_back(static_cast<char>((value >> (8 * i)) & 0xffu));
}
inline void put_little_endian_float(std::string& out, float value) {
  std::uint32_t bits = 0;  // floats and integers share the host's byte order
  std::memcpy(&bits, &value, sizeof bits);
  put_little_endian<std::uint32_t>(out, bits);
}
}  // namespace detail

/// The PLY file's bytes (header and records).
inline std::string ply_bytes(const std::vector<SemanticPoint>& points,
                             const std::string& comment = "cge semantic map") {
  if (comment.find('\n') != std::string::npos) throw std::invalid_argument("ply_bytes: the comment has a newline");
  std::string out = "ply\nformat binary_little_endian 1.0\ncomment " + comment + "\nelement vertex " +
                    std::to_string(points.size()) +
                    "\nproperty float x\nproperty float y\nproperty float z\n"
                    "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                    "property ushort label\nend_header\n";
  out.reserve(out.size() + points.size() * 17);
  for (const SemanticPoint& p : points) {
    for (int k = 0; k < 3; ++k) detail::put_little_endian_float(out, p.position_m[k]);
    out.push_back(static_cast<char>(p.colour.r));
    out.push_back(static_cast<char>(p.colour.g));
    out.push_back(static_cast<char>(p.colour.b));
    detail::put_little_endian<std::uint16_t>(out, p.class_label);
  }
  return out;
}

/// Writes the cloud to `path`. Throws std::invalid_argument when the file exists and !overwrite,
/// std::runtime_error naming the path when it cannot be written.
inline void write_ply(const std::filesystem::path& path, const std::vector<SemanticPoint>& points,
                      bool overwrite = false, const std::string& comment = "cge semantic map") {
  if (!overwrite && std::filesystem::exists(path)) {
    throw std::invalid_argument("write_ply: " + path.string() + " exists (not overwritten)");
  }
  const std::string bytes = ply_bytes(points, comment);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out) throw std::runtime_error("write_ply: cannot write " + path.string());
}

}  // namespace mapping
}  // namespace cge
