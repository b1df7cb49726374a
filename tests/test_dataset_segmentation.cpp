// Tests of the segmentation sources of the pipeline modes: names, the `none` segmenter, the
// factory on a synthetic sequence's mask folders (instances checked against the rendered labels
// and the PNGs read independently), and the errors for missing files.

#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "cge/dataset/segmentation_source.hpp"
#include "cge/segmentation/precomputed_mask_reader.hpp"
#include "cge/segmentation/yolov8_segmenter.hpp"
#include "cge/sim/segmentation_error_model.hpp"
#include "cge/sim/tum_writer.hpp"
#include "dataset_test_support.hpp"
#include "onnx_test_models.hpp"
#include "temp_dir.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using cge::dataset::GroundTruthMasks;
using cge::dataset::make_segmenter;
using cge::dataset::SegmentationSource;
using cge::dataset::SegmentationSourceSettings;
using cge_test::invalid_argument_message;
using cge_test::TempDir;

namespace {

/// Every instance's mask must be exactly the pixels of `labels` with its id, and every non-zero
/// label must have its instance; the class and dynamic flag from the sequence's table.
void check_against_labels(const std::vector<cge::SegmentedInstance>& instances, const cv::Mat& labels,
                          const std::set<int>& dynamic_classes) {
  std::set<int> ids_in_image;
  for (int y = 0; y < labels.rows; ++y)
    for (int x = 0; x < labels.cols; ++x)
      if (labels.at<std::uint16_t>(y, x) != 0) ids_in_image.insert(labels.at<std::uint16_t>(y, x));
  std::set<int> ids_found;
  for (const cge::SegmentedInstance& inst : instances) {
    CAPTURE(inst.id);
    ids_found.insert(inst.id);
    const cv::Mat expected = (labels == inst.id);
    CHECK(cv::countNonZero(expected != inst.mask) == 0);
    CHECK(inst.dynamic == (dynamic_classes.count(inst.class_id) == 1));
  }
  CHECK(ids_found == ids_in_image);
}

}  // namespace

TEST_CASE("Segmentation source: names", "[dataset][segmentation_source]") {
  for (const SegmentationSource s : {SegmentationSource::none, SegmentationSource::ground_truth,
                                     SegmentationSource::yolo, SegmentationSource::precomputed}) {
    CHECK(cge::dataset::parse_segmentation_source(cge::dataset::to_string(s)) == s);
  }
  CHECK(std::string(cge::dataset::to_string(SegmentationSource::ground_truth)) == "ground_truth");
  CHECK_THAT(invalid_argument_message([] { cge::dataset::parse_segmentation_source("mask_rcnn"); }),
             Contains("mask_rcnn") && Contains("none, ground_truth, yolo, precomputed"));
  CHECK(std::string(cge::dataset::folder_name(GroundTruthMasks::exact)) == "masks");
  CHECK(std::string(cge::dataset::folder_name(GroundTruthMasks::after_error_model)) == "segmentation");
}

TEST_CASE("Segmentation source none: no instances, whatever the frame", "[dataset][segmentation_source]") {
  SegmentationSourceSettings settings;
  settings.dynamic_class_ids = {0, 2};
  const auto segmenter = make_segmenter(settings, "/nonexistent");  // none reads no files
  REQUIRE(dynamic_cast<cge::dataset::NoSegmenter*>(segmenter.get()) != nullptr);
  CHECK(segmenter->segment({cv::Mat(4, 5, CV_8UC3, cv::Scalar::all(7)), "x"}).empty());
  CHECK(segmenter->segment({cv::Mat(), ""}).empty());
  CHECK(segmenter->dynamic_classes() == std::set<int>{0, 2});
  segmenter->set_dynamic_classes({56});
  CHECK(segmenter->dynamic_classes() == std::set<int>{56});
  CHECK_THROWS_AS(segmenter->set_dynamic_classes({80}), std::invalid_argument);
}

TEST_CASE("Segmentation source ground_truth and precomputed on a synthetic sequence",
          "[dataset][segmentation_source]") {
  const auto seq = cge_test::tiny_sequence(4);
  cge::sim::SegmentationErrorSettings errors;
  errors.boundary_offset_px = -1;
  errors.false_positive_probability = 0.7;
  errors.false_positive_min_height_fraction = 0.2;
  errors.false_positive_max_height_fraction = 0.4;
  cge::sim::SegmentationErrorModel model(seq.instances(), 9, errors);
  TempDir tmp{"cge_test_dataset_seg"};
  const fs::path dir = tmp.path() / "seq";
  cge::sim::write_tum_sequence(seq, model, dir);

  SegmentationSourceSettings settings;
  settings.source = SegmentationSource::ground_truth;
  settings.ground_truth_masks = GroundTruthMasks::exact;
  const auto exact = make_segmenter(settings, dir);
  settings.ground_truth_masks = GroundTruthMasks::after_error_model;
  const auto noisy = make_segmenter(settings, dir);
  const auto* exact_reader = dynamic_cast<const cge::PrecomputedMaskReader*>(exact.get());
  const auto* noisy_reader = dynamic_cast<const cge::PrecomputedMaskReader*>(noisy.get());
  REQUIRE(exact_reader != nullptr);
  REQUIRE(noisy_reader != nullptr);
  CHECK(fs::path(exact_reader->folder()) == dir / "masks");
  CHECK(fs::path(noisy_reader->folder()) == dir / "segmentation");
  CHECK(exact_reader->settings().require_every_frame);  // ground truth: a missing PNG is an error

  settings.source = SegmentationSource::precomputed;
  settings.mask_folder = (dir / "segmentation").string();
  const auto precomputed = make_segmenter(settings, "/nonexistent");  // the dataset folder is not used
  CHECK_FALSE(dynamic_cast<const cge::PrecomputedMaskReader&>(*precomputed).settings().require_every_frame);

  for (int i = 0; i < seq.frame_count(); ++i) {
    CAPTURE(i);
    const cge::sim::RenderedFrame& truth = seq.frames[static_cast<std::size_t>(i)];
    const std::string stem = cge::sim::format_tum_timestamp(truth.timestamp_s);
    const cge::FrameImage frame{truth.rgb, stem};
    // Exact: the rendered labels themselves; person (class 0) dynamic, chair not.
    const auto exact_instances = exact->segment(frame);
    check_against_labels(exact_instances, truth.instance_labels, {cge::kCocoPerson});
    // After the error model: the PNG the writer wrote, read independently.
    const cv::Mat written = cv::imread((dir / "segmentation" / (stem + ".png")).string(), cv::IMREAD_UNCHANGED);
    REQUIRE(written.type() == CV_16UC1);
    check_against_labels(noisy->segment(frame), written, {cge::kCocoPerson});
    check_against_labels(precomputed->segment(frame), written, {cge::kCocoPerson});
  }
  // Strict ground truth: a frame the simulator did not write is an error, precomputed says "none".
  const cge::FrameImage unknown{seq.frames[0].rgb, "123.000000"};
  CHECK_THROWS_AS(exact->segment(unknown), std::invalid_argument);
  CHECK(precomputed->segment(unknown).empty());
}

TEST_CASE("Segmentation sources: missing files are named", "[dataset][segmentation_source][errors]") {
  TempDir tmp{"cge_test_dataset_seg"};
  const fs::path dir = tmp.path();
  SegmentationSourceSettings settings;

  settings.source = SegmentationSource::ground_truth;
  CHECK_THAT(invalid_argument_message([&] { make_segmenter(settings, dir); }),
             Contains("ground_truth") && Contains((dir / "segmentation").string()) && Contains("does not exist"));
  settings.ground_truth_masks = GroundTruthMasks::exact;
  CHECK_THAT(invalid_argument_message([&] { make_segmenter(settings, dir); }), Contains((dir / "masks").string()));
  fs::create_directories(dir / "masks");
  CHECK_THAT(invalid_argument_message([&] { make_segmenter(settings, dir); }),
             Contains((dir / "masks").string()) && Contains("instances.csv"));
  std::ofstream(dir / "masks" / "instances.csv") << "id,class_id,class_name,moving\n1,99,thing,1\n";
  CHECK_THAT(invalid_argument_message([&] { make_segmenter(settings, dir); }), Contains("instances.csv:2"));

  settings.source = SegmentationSource::precomputed;
  CHECK_THAT(invalid_argument_message([&] { make_segmenter(settings, dir); }),
             Contains("precomputed") && Contains("no mask folder"));
  settings.mask_folder = (dir / "elsewhere").string();
  CHECK_THAT(invalid_argument_message([&] { make_segmenter(settings, dir); }),
             Contains("precomputed") && Contains(settings.mask_folder));

  settings.source = SegmentationSource::yolo;
  CHECK_THAT(invalid_argument_message([&] { make_segmenter(settings, dir); }),
             Contains("yolo") && Contains("no model file"));
  settings.yolo_model_path = (dir / "yolov8n-seg.onnx").string();
  CHECK_THAT(invalid_argument_message([&] { make_segmenter(settings, dir); }),
             Contains("yolo") && Contains(settings.yolo_model_path) && Contains("does not exist"));
  std::ofstream(settings.yolo_model_path) << "not a model";
  CHECK_THAT(invalid_argument_message([&] { make_segmenter(settings, dir); }), Contains(settings.yolo_model_path));

  settings.source = SegmentationSource::none;
  settings.dynamic_class_ids = {80};
  CHECK_THAT(invalid_argument_message([&] { make_segmenter(settings, dir); }), Contains("80"));
}

TEST_CASE("Segmentation source yolo: a YOLOv8-seg-shaped model with the chosen dynamic classes",
          "[dataset][segmentation_source]") {
  namespace onnx = cge_test::onnx;
  TempDir tmp{"cge_test_dataset_seg"};
  onnx::YoloConstants c;  // all zero: no detection reaches the confidence threshold
  c.prediction.assign(cge::kYolov8PredictionRows, 0.f);
  c.prototype.assign(cge::kYolov8MaskCoefficients, 0.f);
  const std::string path = tmp.file("tiny.onnx");
  onnx::write_file(path, onnx::yolo_shaped_model(c));

  SegmentationSourceSettings settings;
  settings.source = SegmentationSource::yolo;
  settings.yolo_model_path = path;
  settings.yolo.confidence_threshold = 0.5f;
  settings.dynamic_class_ids = {0, 56};
  settings.temporal_filter_sources.clear();  // the network alone
  const auto segmenter = make_segmenter(settings, tmp.path());
  const auto* yolo = dynamic_cast<const cge::Yolov8Segmenter*>(segmenter.get());
  REQUIRE(yolo != nullptr);
  CHECK(yolo->model_path() == path);
  CHECK(yolo->settings().confidence_threshold == 0.5f);
  CHECK(yolo->dynamic_classes() == std::set<int>{0, 56});
  cv::Mat image(32, 32, CV_8UC3, cv::Scalar::all(90));
  CHECK(segmenter->segment({image, "frame"}).empty());
}

TEST_CASE("Segmentation sources: the temporal instance filter wraps the sources named for it",
          "[dataset][segmentation_source][temporal_filter]") {
  namespace onnx = cge_test::onnx;
  TempDir tmp{"cge_test_dataset_seg_temporal"};
  onnx::YoloConstants c;
  c.prediction.assign(cge::kYolov8PredictionRows, 0.f);
  c.prototype.assign(cge::kYolov8MaskCoefficients, 0.f);
  const std::string path = tmp.file("tiny.onnx");
  onnx::write_file(path, onnx::yolo_shaped_model(c));

  SegmentationSourceSettings settings;
  CHECK(settings.temporal_filter_sources == std::set<SegmentationSource>{SegmentationSource::yolo});
  settings.source = SegmentationSource::yolo;
  settings.yolo_model_path = path;
  settings.dynamic_class_ids = {0, 2};
  settings.temporal_filter.min_frames_seen = 3;
  settings.temporal_filter.window_frames = 4;
  settings.temporal_filter.overlap = cge::TemporalOverlap::mask;
  const auto segmenter = make_segmenter(settings, tmp.path());
  const auto* filter = dynamic_cast<const cge::TemporalInstanceFilter*>(segmenter.get());
  REQUIRE(filter != nullptr);
  CHECK(filter->settings().min_frames_seen == 3);
  CHECK(filter->settings().window_frames == 4);
  CHECK(filter->settings().overlap == cge::TemporalOverlap::mask);
  const auto* yolo = dynamic_cast<const cge::Yolov8Segmenter*>(&filter->inner());
  REQUIRE(yolo != nullptr);
  CHECK(yolo->model_path() == path);
  CHECK(segmenter->dynamic_classes() == std::set<int>{0, 2});
  cv::Mat image(32, 32, CV_8UC3, cv::Scalar::all(90));
  CHECK(segmenter->segment({image, "frame"}).empty());

  // The none source is not named: no wrapper. Named, it is wrapped.
  SegmentationSourceSettings none;
  CHECK(dynamic_cast<const cge::dataset::NoSegmenter*>(make_segmenter(none, tmp.path()).get()) != nullptr);
  none.temporal_filter_sources = {SegmentationSource::none};
  CHECK(dynamic_cast<const cge::TemporalInstanceFilter*>(make_segmenter(none, tmp.path()).get()) != nullptr);

  // Bad filter settings are named, but only when a source is filtered.
  settings.temporal_filter.min_frames_seen = 5;
  CHECK_THAT(invalid_argument_message([&] { make_segmenter(settings, tmp.path()); }),
             Contains("temporal_filter") && Contains("min_frames_seen"));
  settings.temporal_filter_sources.clear();
  CHECK_NOTHROW(make_segmenter(settings, tmp.path()));
}
