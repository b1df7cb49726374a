#include "cge/segmentation/precomputed_mask_reader.hpp"

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <istream>
#include <limits>
#include <stdexcept>
#include <string_view>

#include <opencv2/imgcodecs.hpp>

namespace cge {
namespace {

constexpr std::string_view kHeader = "id,class_id,class_name,moving";
constexpr std::size_t kFieldCount = 4;
constexpr int kMaxInstanceId = std::numeric_limits<std::uint16_t>::max();
constexpr const char* kInstancesFile = "instances.csv";
constexpr const char* kMaskExtension = ".png";

std::string_view trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t");
  if (first == std::string_view::npos) return {};
  const auto last = s.find_last_not_of(" \t");
  return s.substr(first, last - first + 1);
}

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    fields.push_back(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start));
    if (comma == std::string_view::npos) return fields;
    start = comma + 1;
  }
}

std::optional<int> parse_int(std::string_view s) {
  int value = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (s.empty() || ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return value;
}

}  // namespace

std::map<int, MaskFolderInstance> read_instances_csv(std::istream& in, const std::string& source) {
  std::map<int, MaskFolderInstance> out;
  std::string raw;
  int line_number = 0;
  bool header_seen = false;
  const auto fail = [&](const std::string& what) {
    throw std::invalid_argument(source + ":" + std::to_string(line_number) + ": " + what);
  };
  while (std::getline(in, raw)) {
    ++line_number;
    std::string_view line(raw);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);  // written on Windows
    if (line.empty() || line.front() == '#') continue;
    if (!header_seen) {
      if (line != kHeader)
        fail("expected the header '" + std::string(kHeader) + "', found '" + std::string(line) + "'");
      header_seen = true;
      continue;
    }
    const auto fields = split(line);
    if (fields.size() != kFieldCount) {
      fail("expected 4 comma-separated fields (id,class_id,class_name,moving), found " + std::to_string(fields.size()));
    }
    MaskFolderInstance instance;
    instance.line = line_number;
    const std::string_view id_text = trim(fields[0]), class_text = trim(fields[1]), moving_text = trim(fields[3]);
    const auto id = parse_int(id_text);
    if (!id || *id < 1 || *id > kMaxInstanceId)
      fail("id '" + std::string(id_text) + "' is not an integer in 1 .. 65535");
    instance.id = *id;
    const auto class_id = parse_int(class_text);
    if (!class_id || *class_id < 0 || *class_id >= kCocoClassCount) {
      fail("class_id '" + std::string(class_text) + "' is not a COCO class id (an integer in 0 .. 79)");
    }
    instance.class_id = *class_id;
    instance.class_name = std::string(trim(fields[2]));
    if (moving_text == "1") {
      instance.moving = true;
    } else if (moving_text == "0") {
      instance.moving = false;
    } else if (!moving_text.empty()) {
      fail("moving '" + std::string(moving_text) + "' is not 1, 0 or empty");
    }
    const auto [it, inserted] = out.emplace(instance.id, instance);
    if (!inserted) fail("id " + std::to_string(instance.id) + " repeats line " + std::to_string(it->second.line));
  }
  if (in.bad()) fail("read error");
  if (!header_seen) {
    throw std::invalid_argument(source + ": empty, expected at least the header '" + std::string(kHeader) + "'");
  }
  return out;
}

PrecomputedMaskReader::PrecomputedMaskReader(const std::string& folder, PrecomputedMaskSettings settings)
    : folder_(folder), settings_(std::move(settings)) {
  namespace fs = std::filesystem;
  check_coco_class_ids(settings_.dynamic_class_ids, "PrecomputedMaskSettings");
  std::error_code ec;
  if (!fs::is_directory(folder_, ec)) {
    throw std::invalid_argument("PrecomputedMaskReader: mask folder " + folder_ + " does not exist or is not a folder");
  }
  const std::string csv = (fs::path(folder_) / kInstancesFile).string();
  std::ifstream in(csv);
  if (!in) throw std::invalid_argument("PrecomputedMaskReader: cannot open " + csv);
  instances_ = read_instances_csv(in, csv);
}

std::vector<SegmentedInstance> PrecomputedMaskReader::segment(const FrameImage& frame) {
  if (frame.bgr.empty()) {
    throw std::invalid_argument("PrecomputedMaskReader: frame '" + frame.stem +
                                "': the image is empty (its size is needed to check the mask)");
  }
  return read(frame.stem, frame.bgr.size());
}

std::vector<SegmentedInstance> PrecomputedMaskReader::read(const std::string& stem, cv::Size image_size) const {
  namespace fs = std::filesystem;
  if (stem.empty() || stem.find_first_of("/\\") != std::string::npos) {
    throw std::invalid_argument("PrecomputedMaskReader: frame name '" + stem +
                                "' is not a file stem (empty or with a path separator)");
  }
  const std::string path = (fs::path(folder_) / (stem + kMaskExtension)).string();
  std::error_code ec;
  if (!fs::exists(path, ec)) {
    if (settings_.require_every_frame) {
      throw std::invalid_argument("PrecomputedMaskReader: no mask image " + path + " for frame '" + stem + "'");
    }
    return {};
  }
  const cv::Mat raw = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (raw.empty()) throw std::invalid_argument("PrecomputedMaskReader: " + path + " cannot be read as an image");
  if (raw.type() != CV_16UC1 && raw.type() != CV_8UC1) {
    throw std::invalid_argument("PrecomputedMaskReader: " + path + " is " + cv::typeToString(raw.type()) +
                                ", expected a single-channel 16-bit (or 8-bit) instance-label image");
  }
  if (raw.size() != image_size) {
    throw std::invalid_argument("PrecomputedMaskReader: " + path + " is " + std::to_string(raw.cols) + " x " +
                                std::to_string(raw.rows) + " pixels but the frame is " +
                                std::to_string(image_size.width) + " x " + std::to_string(image_size.height));
  }
  cv::Mat labels;
  raw.convertTo(labels, CV_16U);

  // Bounding box of every id present, in one pass.
  struct Bounds {
    int x0, y0, x1, y1;  // inclusive
  };
  std::map<int, Bounds> present;
  for (int y = 0; y < labels.rows; ++y) {
    const std::uint16_t* row = labels.ptr<std::uint16_t>(y);
    for (int x = 0; x < labels.cols; ++x) {
      if (row[x] == 0) continue;
      const auto [it, inserted] = present.try_emplace(row[x], Bounds{x, y, x, y});
      if (inserted) {
        if (instances_.count(row[x]) == 0) {
          throw std::invalid_argument("PrecomputedMaskReader: " + path + " uses instance id " + std::to_string(row[x]) +
                                      " (first at x " + std::to_string(x) + ", y " + std::to_string(y) +
                                      "), which is not in instances.csv");
        }
        continue;
      }
      Bounds& b = it->second;
      b.x0 = std::min(b.x0, x);
      b.x1 = std::max(b.x1, x);
      b.y1 = y;  // rows are visited in order
    }
  }

  std::vector<SegmentedInstance> out;
  out.reserve(present.size());
  for (const auto& [id, b] : present) {
    const MaskFolderInstance& info = instances_.at(id);
    SegmentedInstance instance;
    instance.id = id;
    instance.class_id = info.class_id;
    instance.score = 1;
    instance.box_px = cv::Rect2f(static_cast<float>(b.x0), static_cast<float>(b.y0),
                                 static_cast<float>(b.x1 - b.x0 + 1), static_cast<float>(b.y1 - b.y0 + 1));
    cv::compare(labels, cv::Scalar(id), instance.mask, cv::CMP_EQ);
    instance.dynamic = settings_.dynamic_class_ids.count(info.class_id) > 0;
    instance.moving = info.moving;
    out.push_back(std::move(instance));
  }
  return out;
}

void PrecomputedMaskReader::set_dynamic_classes(const std::set<int>& class_ids) {
  check_coco_class_ids(class_ids, "PrecomputedMaskReader::set_dynamic_classes");
  settings_.dynamic_class_ids = class_ids;
}

}  // namespace cge
