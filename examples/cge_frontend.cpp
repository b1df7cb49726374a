// cge_frontend: the dynamic-feature front end on one RGB-D frame. ORB features, instance
// segmentation (a YOLOv8-seg model, or a precomputed instance-label PNG, or none), the
// DepthMADFilter (docs/METHOD.md section 1), a JSON report on standard output and, on request, a
// picture of the result. See docs/CLI.md.
//
// Exit codes: 0 success; 1 a failure after the input was accepted (writing the picture or standard
// output); 2 bad usage or bad input (the message names the flag or the file).

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "cge/frontend/depth_mad_filter.hpp"
#include "cge/opencv/depth.hpp"
#include "cge/opencv/keypoint.hpp"
#include "cge/opencv/mask.hpp"
#include "cge/opencv/pixel_box.hpp"
#include "cge/segmentation/coco_classes.hpp"
#include "cge/segmentation/instance_segmenter.hpp"
#include "cge/segmentation/precomputed_mask_reader.hpp"
#include "cge/segmentation/yolov8_segmenter.hpp"

#include "cge/dataset/orbslam2_settings.hpp"
#include "cge/io/stderr_capture.hpp"
#include "tool_support.hpp"

#ifndef CGE_VERSION_STRING
#define CGE_VERSION_STRING "unknown"
#endif

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;  // keys in insertion order: the output's order is fixed
using Clock = std::chrono::steady_clock;

using cge_tool::kExitFailure;
using cge_tool::kExitOk;
constexpr const char* kProgram = "cge_frontend";

// Defaults of the flags.
constexpr int kDefaultFeatures = 1000;     // ORB features per frame (cv::ORB's default 500 is sparse)
constexpr std::uint64_t kDefaultSeed = 0;  // the MAD sampling engine's seed
constexpr const char* kDefaultDynamic = "person";

// Output precision: decimals kept of each kind of value, so that no float noise is printed.
constexpr int kPixelDecimals = 3;  // boxes, pixels
constexpr int kMetreDecimals = 6;  // depths, metres (the TUM depth unit is 2e-4 m)
constexpr int kScoreDecimals = 6;  // detection scores and thresholds
constexpr int kMsDecimals = 3;     // timings, milliseconds

// The picture: colours (BGR) and sizes.
const cv::Scalar kStaticColour(0, 220, 0);       // green
const cv::Scalar kMaskColour(0, 0, 255);         // red
const cv::Scalar kMadColour(0, 230, 255);        // yellow
const cv::Scalar kOutlineColour(0, 0, 0);        // feature outlines and label text
const cv::Scalar kLegendBackground(40, 40, 40);  // dark grey
const std::array<cv::Scalar, 6> kInstancePalette = {cv::Scalar(255, 140, 30), cv::Scalar(200, 60, 200),
                                                    cv::Scalar(255, 255, 60), cv::Scalar(150, 90, 255),
                                                    cv::Scalar(60, 160, 255), cv::Scalar(180, 180, 60)};
constexpr double kDynamicAlpha = 0.45;  // mask opacity of instances of dynamic classes
constexpr double kStaticAlpha = 0.2;    // mask opacity of the other instances
constexpr int kFeatureRadiusPx = 3;
constexpr double kFontScale = 0.45;
constexpr int kTextPaddingPx = 3;

/// A bad flag or input, reported on stderr with exit code 2.
using cge_tool::UsageError;

struct Options {
  std::string rgb, depth, model, masks, out_image;
  int features = kDefaultFeatures;
  std::uint64_t seed = kDefaultSeed;
  double mad_scale = cge::DepthMADSettings().mad_scale;
  std::string depth_estimate = cge::to_string(cge::DepthMADSettings().depth_estimate);
  double depth_scale = cge::opencv::tum_depth_units_per_metre;
  std::vector<std::string> dynamic_classes = {kDefaultDynamic};
  float mask_threshold = cge::Yolov8Settings().mask_threshold;
  std::string mask_decoding = cge::to_string(cge::Yolov8Settings().mask_decoding);
  bool force = false;
};

/// A JSON number: the double nearest to `value` rounded to `decimals` decimal places, which the
/// JSON writer prints in its shortest form (356.965, not 356.96500000000003); null when the value
/// is not finite (JSON has no NaN). The program never sets a locale, so printf uses a decimal point.
Json number(double value, int decimals) {
  if (!std::isfinite(value)) return Json(nullptr);
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, value);
  return Json(std::strtod(text, nullptr));
}

double elapsed_ms(Clock::time_point since) {
  return std::chrono::duration<double, std::milli>(Clock::now() - since).count();
}

/// Throws a UsageError naming the flag unless `path` names an existing regular file.
void require_file(const char* flag, const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw UsageError(std::string(flag) + ": file '" + path + "' does not exist");
  if (fs::is_directory(path, ec)) throw UsageError(std::string(flag) + ": '" + path + "' is a directory, not a file");
}

std::set<int> dynamic_class_ids(const std::vector<std::string>& names) {
  if (names.empty()) throw UsageError("--dynamic-classes: give at least one COCO class name (e.g. person)");
  std::set<int> ids;
  for (const std::string& name : names) {
    const std::optional<int> id = cge::coco_class_id(name);
    if (!id) {
      throw UsageError("--dynamic-classes: '" + name +
                       "' is not a COCO class name (lower case, as YOLOv8 spells them: person, chair, tv, ...)");
    }
    ids.insert(*id);
  }
  return ids;
}

void check_options(const Options& opt) {
  if (opt.features < 1) throw UsageError("--features must be at least 1, got " + std::to_string(opt.features));
  cge_tool::require_at_most("--features", opt.features, cge::dataset::kMaxOrbFeatures,
                            "the ORB extractor reserves memory per feature");
  if (!(std::isfinite(opt.mad_scale) && opt.mad_scale >= 0)) {
    throw UsageError("--mad-scale must be a finite number >= 0, got " + std::to_string(opt.mad_scale));
  }
  if (!(std::isfinite(opt.depth_scale) && opt.depth_scale > 0)) {
    throw UsageError("--depth-scale must be a finite number > 0 (units per metre; TUM: 5000), got " +
                     std::to_string(opt.depth_scale));
  }
  if (!(opt.mask_threshold > 0 && opt.mask_threshold < 1)) {
    throw UsageError("--mask-threshold must lie in (0, 1), got " + std::to_string(opt.mask_threshold));
  }
  if (!opt.out_image.empty()) {
    std::error_code ec;
    if (fs::exists(opt.out_image, ec) && !opt.force) {
      throw UsageError("--out-image: '" + opt.out_image +
                       "' exists; refusing to overwrite it (add --force to replace it)");
    }
    if (fs::is_directory(opt.out_image, ec)) throw UsageError("--out-image: '" + opt.out_image + "' is a directory");
    if (!cv::haveImageWriter(opt.out_image)) {
      throw UsageError("--out-image: OpenCV cannot write an image named '" + opt.out_image +
                       "' (use an extension such as .png or .jpg)");
    }
  }
}

/// cv::imread with the decoders' own complaints (libpng's "Read Error") kept off standard error:
/// they join the tool's message instead of preceding it.
cv::Mat read_image(const std::string& flag, const std::string& path, int flags) {
  cge::io::StderrCapture decoder_messages;
  const cv::Mat image = cv::imread(path, flags);
  const std::string said = decoder_messages.finish();
  if (image.empty()) {
    throw UsageError(flag + ": cannot read '" + path + "' as an image" + (said.empty() ? "" : " (" + said + ")"));
  }
  return image;
}

cv::Mat load_rgb(const std::string& path) {
  require_file("--rgb", path);
  return read_image("--rgb", path, cv::IMREAD_COLOR);
}

cv::Mat load_depth(const std::string& path, cv::Size image_size, const std::string& rgb_path) {
  require_file("--depth", path);
  const cv::Mat depth = read_image("--depth", path, cv::IMREAD_UNCHANGED);
  if (depth.type() != CV_16UC1) {
    throw UsageError("--depth: '" + path + "' is " + cv::typeToString(depth.type()) +
                     ", expected a single-channel 16-bit image (CV_16UC1, e.g. a TUM depth PNG)");
  }
  if (depth.size() != image_size) {
    throw UsageError("--depth: '" + path + "' is " + std::to_string(depth.cols) + " x " + std::to_string(depth.rows) +
                     " pixels but --rgb '" + rgb_path + "' is " + std::to_string(image_size.width) + " x " +
                     std::to_string(image_size.height));
  }
  return depth;
}

/// The segmenter the flags ask for, or nothing (no instances). `described` receives what the
/// output says about the segmentation source.
std::unique_ptr<cge::InstanceSegmenter> make_segmenter(const Options& opt, const std::set<int>& dynamic,
                                                       Json& described, std::string& masks_stem) {
  if (!opt.model.empty()) {
    require_file("--model", opt.model);
    cge::Yolov8Settings settings;
    settings.mask_threshold = opt.mask_threshold;
    settings.mask_decoding =
        opt.mask_decoding == "retina" ? cge::Yolov8MaskDecoding::retina : cge::Yolov8MaskDecoding::prototype_crop;
    settings.dynamic_class_ids = dynamic;
    auto segmenter = std::make_unique<cge::Yolov8Segmenter>(opt.model, settings);
    described["source"] = "yolov8";
    described["model"] = opt.model;
    described["input_size"] = {segmenter->input_size().width, segmenter->input_size().height};
    described["confidence_threshold"] = number(settings.confidence_threshold, kScoreDecimals);
    described["mask_threshold"] = number(settings.mask_threshold, kScoreDecimals);
    described["mask_decoding"] = cge::to_string(settings.mask_decoding);
    return segmenter;
  }
  if (!opt.masks.empty()) {
    require_file("--masks", opt.masks);
    const fs::path path(opt.masks);
    if (path.extension() != ".png") {
      throw UsageError("--masks: '" + opt.masks + "' is not a .png file (an instance-label PNG of a mask folder)");
    }
    cge::PrecomputedMaskSettings settings;
    settings.dynamic_class_ids = dynamic;
    settings.require_every_frame = true;
    const std::string folder = path.has_parent_path() ? path.parent_path().string() : std::string(".");
    masks_stem = path.stem().string();
    described["source"] = "masks";
    described["masks"] = opt.masks;
    described["instances_csv"] = (fs::path(folder) / "instances.csv").string();
    return std::make_unique<cge::PrecomputedMaskReader>(folder, settings);
  }
  described["source"] = "none";
  described["note"] = "neither --model nor --masks was given: no instances, every feature is static";
  return nullptr;
}

cv::Scalar label_colour(cge::FeatureLabel label) {
  switch (label) {
    case cge::FeatureLabel::static_feature:
      return kStaticColour;
    case cge::FeatureLabel::dynamic_by_mask:
      return kMaskColour;
    case cge::FeatureLabel::dynamic_by_mad:
      return kMadColour;
  }
  return kOutlineColour;
}

/// Text with a filled background whose top-left corner is `origin`, moved left as far as needed to
/// keep it on the canvas.
void draw_label(cv::Mat& canvas, const std::string& text, cv::Point origin, const cv::Scalar& background,
                const cv::Scalar& foreground) {
  int baseline = 0;
  const cv::Size size = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, kFontScale, 1, &baseline);
  const cv::Size area_size(size.width + 2 * kTextPaddingPx, size.height + baseline + 2 * kTextPaddingPx);
  origin.x = std::max(0, std::min(origin.x, canvas.cols - area_size.width));
  const cv::Rect area(origin, area_size);
  cv::rectangle(canvas, area, background, cv::FILLED);
  cv::putText(canvas, text, origin + cv::Point(kTextPaddingPx, kTextPaddingPx + size.height), cv::FONT_HERSHEY_SIMPLEX,
              kFontScale, foreground, 1, cv::LINE_AA);
}

/// The picture: instance masks tinted in one colour each (more opaque for dynamic classes), their
/// boxes and class labels, the features coloured by label, and a legend with the counts.
cv::Mat draw(const cv::Mat& image, const std::vector<cge::SegmentedInstance>& instances,
             const std::vector<cv::KeyPoint>& keypoints, const cge::DepthMADResult& result) {
  cv::Mat canvas = image.clone();
  for (std::size_t i = 0; i < instances.size(); ++i) {
    const cge::SegmentedInstance& s = instances[i];
    const cv::Scalar colour = kInstancePalette[i % kInstancePalette.size()];
    const double alpha = s.dynamic ? kDynamicAlpha : kStaticAlpha;
    cv::Mat tinted;
    cv::addWeighted(canvas, 1 - alpha, cv::Mat(canvas.size(), canvas.type(), colour), alpha, 0, tinted);
    tinted.copyTo(canvas, s.mask);
  }
  for (std::size_t i = 0; i < instances.size(); ++i) {
    const cge::SegmentedInstance& s = instances[i];
    const cv::Scalar colour = kInstancePalette[i % kInstancePalette.size()];
    const cv::Rect box(cv::Point(static_cast<int>(std::floor(s.box_px.x)), static_cast<int>(std::floor(s.box_px.y))),
                       cv::Point(static_cast<int>(std::ceil(s.box_px.x + s.box_px.width)) - 1,
                                 static_cast<int>(std::ceil(s.box_px.y + s.box_px.height)) - 1));
    cv::rectangle(canvas, box, colour, s.dynamic ? 2 : 1);
    char score[16];
    std::snprintf(score, sizeof score, "%.2f", static_cast<double>(s.score));
    const std::string text = "#" + std::to_string(s.id) + " " + std::string(cge::coco_class_name(s.class_id)) + " " +
                             score + (s.dynamic ? " (dynamic)" : "");
    draw_label(canvas, text, box.tl(), colour, kOutlineColour);
  }
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    const cv::Point centre(static_cast<int>(std::lround(keypoints[i].pt.x)),
                           static_cast<int>(std::lround(keypoints[i].pt.y)));
    cv::circle(canvas, centre, kFeatureRadiusPx, label_colour(result.labels[i]), cv::FILLED, cv::LINE_AA);
    cv::circle(canvas, centre, kFeatureRadiusPx, kOutlineColour, 1, cv::LINE_AA);
  }
  const std::pair<cge::FeatureLabel, const char*> legend[] = {{cge::FeatureLabel::static_feature, "static"},
                                                              {cge::FeatureLabel::dynamic_by_mask, "dynamic (mask)"},
                                                              {cge::FeatureLabel::dynamic_by_mad, "dynamic (MAD)"}};
  int y = canvas.rows;
  for (auto it = std::rbegin(legend); it != std::rend(legend); ++it) {
    int baseline = 0;
    const int height = cv::getTextSize("Ag", cv::FONT_HERSHEY_SIMPLEX, kFontScale, 1, &baseline).height + baseline +
                       2 * kTextPaddingPx;
    y -= height;
    draw_label(canvas, std::string(it->second) + ": " + std::to_string(result.count(it->first)), cv::Point(0, y),
               kLegendBackground, label_colour(it->first));
  }
  return canvas;
}

int run(const Options& opt) {
  const Clock::time_point start = Clock::now();
  check_options(opt);
  const std::set<int> dynamic = dynamic_class_ids(opt.dynamic_classes);

  // Load: the images, then the segmenter (a YOLOv8 model runs one test pass when it loads).
  const cv::Mat image = load_rgb(opt.rgb);
  const cv::Mat depth = load_depth(opt.depth, image.size(), opt.rgb);
  Json segmentation;
  std::string masks_stem;
  const std::unique_ptr<cge::InstanceSegmenter> segmenter = make_segmenter(opt, dynamic, segmentation, masks_stem);
  const double load_ms = elapsed_ms(start);

  // ORB on the grey image.
  Clock::time_point t = Clock::now();
  cv::Mat grey;
  cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  std::vector<cv::KeyPoint> keypoints;
  cv::ORB::create(opt.features)->detect(grey, keypoints);
  const double orb_ms = elapsed_ms(t);

  // Segmentation. A mask file names its frame by its own stem, not the RGB file's.
  t = Clock::now();
  std::vector<cge::SegmentedInstance> instances;
  if (segmenter) {
    const std::string stem = masks_stem.empty() ? cge::frame_stem(opt.rgb) : masks_stem;
    instances = segmenter->segment(cge::FrameImage{image, stem});
  }
  const double segmentation_ms = elapsed_ms(t);

  // The filter on the dynamic instances.
  t = Clock::now();
  std::vector<cge::DynamicInstance<cv::Mat>> dynamic_instances;
  std::vector<int> stats_index(instances.size(), -1);  // instance -> its record in the filter's result
  for (std::size_t i = 0; i < instances.size(); ++i) {
    if (!instances[i].dynamic) continue;
    stats_index[i] = static_cast<int>(dynamic_instances.size());
    dynamic_instances.push_back(
        cge::dynamic_instance(instances[i].mask, cge::filter_box(instances[i], image.size()), instances[i].class_id));
  }
  cge::DepthMADSettings mad_settings;
  mad_settings.mad_scale = opt.mad_scale;
  mad_settings.depth_estimate =
      opt.depth_estimate == "mask_pixels" ? cge::DepthEstimate::mask_pixels : cge::DepthEstimate::box_samples;
  cge::DepthMADFilter<> filter(mad_settings);
  filter.engine.seed(opt.seed);
  const cge::DepthMADResult result =
      filter.filter(keypoints, cge::opencv::DepthView::from_u16(depth, opt.depth_scale), dynamic_instances);
  const double filter_ms = elapsed_ms(t);

  if (!opt.out_image.empty()) {
    const cv::Mat picture = draw(image, instances, keypoints, result);
    std::error_code ec;
    if (fs::exists(opt.out_image, ec) && !opt.force) {  // appeared while we worked
      throw UsageError("--out-image: '" + opt.out_image +
                       "' exists; refusing to overwrite it (add --force to replace it)");
    }
    // Missing folders on the way are created (docs/CLI.md); the picture replaces the file whole.
    cge_tool::CreatedFolders folders;
    folders.create_parent_of(opt.out_image, "--out-image");
    try {
      cge_tool::replace_file(opt.out_image, [&picture](const fs::path& temporary) {
        return cv::imwrite(temporary.string(), picture);
      });
    } catch (const std::runtime_error&) {
      std::fprintf(stderr, "%s: error: --out-image: cannot write '%s'\n", kProgram, opt.out_image.c_str());
      return kExitFailure;
    }
    folders.keep();
  }
  const double total_ms = elapsed_ms(start);

  Json out;
  out["tool"] = kProgram;
  out["version"] = CGE_VERSION_STRING;
  out["input"] = {{"rgb", opt.rgb},
                  {"depth", opt.depth},
                  {"width_px", image.cols},
                  {"height_px", image.rows},
                  {"depth_units_per_metre", opt.depth_scale}};
  std::vector<std::string> dynamic_names;
  for (const int id : dynamic) dynamic_names.emplace_back(cge::coco_class_name(id));
  segmentation["dynamic_classes"] = dynamic_names;
  out["segmentation"] = segmentation;
  out["filter"] = {{"seed", opt.seed},
                   {"mad_scale", opt.mad_scale},
                   {"samples_per_instance", mad_settings.samples_per_instance},
                   {"disc_radius_px", mad_settings.disc_radius_px},
                   {"min_valid_samples", mad_settings.min_valid_samples},
                   {"depth_estimate", cge::to_string(mad_settings.depth_estimate)}};
  if (mad_settings.depth_estimate == cge::DepthEstimate::mask_pixels) {
    out["filter"]["min_valid_mask_fraction"] = number(mad_settings.min_valid_mask_fraction, kScoreDecimals);
  }
  Json list = Json::array();
  for (std::size_t i = 0; i < instances.size(); ++i) {
    const cge::SegmentedInstance& s = instances[i];
    Json item;
    item["id"] = s.id;
    item["class_id"] = s.class_id;
    item["class_name"] = std::string(cge::coco_class_name(s.class_id));
    item["score"] = number(s.score, kScoreDecimals);
    item["dynamic"] = s.dynamic;
    item["box_px"] = {{"x_min", number(s.box_px.x, kPixelDecimals)},
                      {"y_min", number(s.box_px.y, kPixelDecimals)},
                      {"width", number(s.box_px.width, kPixelDecimals)},
                      {"height", number(s.box_px.height, kPixelDecimals)}};
    item["mask_area_px"] = cv::countNonZero(s.mask);
    if (stats_index[i] >= 0) {
      const cge::InstanceDepthStats& st = result.instances[static_cast<std::size_t>(stats_index[i])];
      item["mad"] = {{"samples_drawn", st.samples_drawn},
                     {"valid_samples", st.valid_samples},
                     {"samples_off_mask", st.samples_off_mask},
                     {"samples_invalid_depth", st.samples_invalid_depth},
                     {"mean_depth_m", number(st.mean_depth_m, kMetreDecimals)},
                     {"mad_m", number(st.mad_m, kMetreDecimals)},
                     {"mad_test_applied", st.mad_test_applied}};
      // Why the depth test skipped the instance, with the figure that fell short and its minimum.
      Json skipped = nullptr;
      if (st.skip_reason == cge::MadSkipReason::too_few_valid_samples) {
        skipped = {{"reason", cge::to_string(st.skip_reason)},
                   {"valid_samples", st.valid_samples},
                   {"min_valid_samples", mad_settings.min_valid_samples}};
      } else if (st.skip_reason == cge::MadSkipReason::too_little_depth_in_mask) {
        skipped = {{"reason", cge::to_string(st.skip_reason)},
                   {"valid_fraction", number(static_cast<double>(st.valid_samples) / st.samples_drawn, kScoreDecimals)},
                   {"min_valid_mask_fraction", number(mad_settings.min_valid_mask_fraction, kScoreDecimals)}};
      }
      item["mad"]["mad_skipped"] = skipped;
    } else {
      item["mad"] = nullptr;  // not a dynamic class: the filter does not look at it
    }
    list.push_back(item);
  }
  out["instances"] = list;
  out["features"] = {{"detected", keypoints.size()},
                     {"static", result.static_count},
                     {"dynamic_by_mask", result.dynamic_by_mask_count},
                     {"dynamic_by_mad", result.dynamic_by_mad_count}};
  out["timings_ms"] = {{"load", number(load_ms, kMsDecimals)},
                       {"orb", number(orb_ms, kMsDecimals)},
                       {"segmentation", number(segmentation_ms, kMsDecimals)},
                       {"filter", number(filter_ms, kMsDecimals)},
                       {"total", number(total_ms, kMsDecimals)}};
  if (!opt.out_image.empty()) out["out_image"] = opt.out_image;

  std::cout << out.dump(2) << '\n';
  if (!cge_tool::standard_output_written(kProgram)) return kExitFailure;
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  CLI::App app{"The dynamic-feature front end on one RGB-D frame (cge " CGE_VERSION_STRING
               "): ORB features, instance segmentation\n"
               "(a YOLOv8-seg ONNX model, a precomputed instance-label PNG, or none) and the DepthMADFilter\n"
               "(masks + MAD of depth). Prints a JSON report; --out-image draws the result. See docs/CLI.md.",
               kProgram};
  app.set_version_flag("--version", std::string(kProgram) + " " + CGE_VERSION_STRING);
  app.add_option("--rgb", opt.rgb, "colour image (any format OpenCV reads)")->required();
  app.add_option("--depth", opt.depth, "16-bit depth PNG of the same size (see --depth-scale)")->required();
  CLI::Option* model = app.add_option("--model", opt.model, "YOLOv8-seg ONNX model (fixed input size)");
  CLI::Option* masks =
      app.add_option("--masks", opt.masks, "instance-label PNG of a mask folder (its instances.csv beside it)");
  model->excludes(masks);
  app.add_option("--features", opt.features, "ORB features to detect, >= 1")->capture_default_str();
  // CLI11 would wrap "-3" around to 2^64 - 3: refuse a sign first.
  const CLI::Validator unsigned_integer(
      [](const std::string& text) {
        return text.find('-') == std::string::npos ? std::string() : "must not be negative, got " + text;
      },
      "UINT64");
  app.add_option("--seed", opt.seed, "seed of the MAD sampling engine, 0 .. 2^64 - 1")
      ->check(unsigned_integer)
      ->capture_default_str();
  app.add_option("--mad-scale", opt.mad_scale, "k: dynamic when |d - mean| < k MAD, >= 0")->capture_default_str();
  app.add_option("--depth-estimate", opt.depth_estimate,
                 "where a person's depth statistics come from: box_samples (n random samples in the box, the "
                 "paper's) or mask_pixels (every mask pixel with depth; docs/SEGMENTATION.md)")
      ->check(CLI::IsMember({"box_samples", "mask_pixels"}))
      ->capture_default_str();
  app.add_option("--depth-scale", opt.depth_scale, "depth units per metre (TUM: 5000), > 0")->capture_default_str();
  app.add_option("--dynamic-classes", opt.dynamic_classes, "COCO class names treated as dynamic, comma-separated")
      ->delimiter(',')
      ->capture_default_str();
  app.add_option("--mask-threshold", opt.mask_threshold, "mask probability threshold of the model, in (0, 1)")
      ->capture_default_str()
      ->needs(model);
  app.add_option("--mask-decoding", opt.mask_decoding,
                 "mask decoding order of the model: prototype_crop or retina (docs/SEGMENTATION.md)")
      ->check(CLI::IsMember({"prototype_crop", "retina"}))
      ->capture_default_str()
      ->needs(model);
  CLI::Option* out_image = app.add_option("--out-image", opt.out_image,
                                          "write a picture of the result here (never over a file without --force)");
  app.add_flag("--force", opt.force, "let --out-image replace an existing file")->needs(out_image);

  if (const int exit_code = cge_tool::parse_command_line(app, argc, argv, kProgram); exit_code >= 0) return exit_code;

  return cge_tool::run_reporting_errors(kProgram, nullptr, [&] { return run(opt); });
}
