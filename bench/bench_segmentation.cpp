// The segmentation front end (docs/SEGMENTATION.md): Yolov8Segmenter::segment on a real TUM frame
// with both shared models, the decoding step alone, and PrecomputedMaskReader::read. The models and
// the frame come from ../shared; without them the benchmarks report an error and do not run.

#include <benchmark/benchmark.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include <opencv2/dnn.hpp>
#include <opencv2/imgcodecs.hpp>

#include "cge/segmentation/precomputed_mask_reader.hpp"
#include "cge/segmentation/yolov8_segmenter.hpp"

namespace {

const std::string kFrame = "1341846313.592026";

std::string shared_file(const std::string& relative) { return std::string(CGE_SHARED_DIR) + "/" + relative; }

std::string model_path(int side) { return shared_file("models/yolov8n-seg-" + std::to_string(side) + ".onnx"); }

cv::Mat tum_frame() {
  return cv::imread(shared_file("data/tum_fr3_walking_xyz/rgb/" + kFrame + ".png"), cv::IMREAD_COLOR);
}

// ---- Yolov8Segmenter::segment: letterbox, forward pass, decoding -------------------------------------

void BM_Yolov8Segment(benchmark::State& state) {
  const int side = static_cast<int>(state.range(0));
  const cv::Mat image = tum_frame();
  if (!std::filesystem::exists(model_path(side)) || image.empty()) {
    state.SkipWithError("../shared models or TUM frame absent");
    return;
  }
  cge::Yolov8Segmenter segmenter(model_path(side));
  std::size_t instances = 0;
  for (auto _ : state) {
    const auto out = segmenter.segment({image, kFrame});
    instances = out.size();
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["instances"] = static_cast<double>(instances);
}
BENCHMARK(BM_Yolov8Segment)->Arg(320)->Arg(640)->Unit(benchmark::kMillisecond)->MinTime(2.0)->MeasureProcessCPUTime();

// ---- decode_yolov8_seg alone, on the outputs of the same frame ------------------------------------------

void BM_Yolov8Decode(benchmark::State& state) {
  const int side = static_cast<int>(state.range(0));
  const cv::Mat image = tum_frame();
  if (!std::filesystem::exists(model_path(side)) || image.empty()) {
    state.SkipWithError("../shared models or TUM frame absent");
    return;
  }
  cv::dnn::Net net = cv::dnn::readNetFromONNX(model_path(side));
  const cge::Letterbox lb = cge::make_letterbox(image.size(), {side, side});
  const cge::Yolov8Settings settings;
  net.setInput(cv::dnn::blobFromImage(cge::letterbox_image(image, lb, settings.pad_value), 1.0 / 255, cv::Size(),
                                      cv::Scalar(), true, false, CV_32F));
  std::vector<cv::Mat> outputs;
  net.forward(outputs, net.getUnconnectedOutLayersNames());
  const bool first_is_predictions = outputs[0].dims == 3;
  const cv::Mat predictions = outputs[first_is_predictions ? 0 : 1].clone();
  const cv::Mat prototypes = outputs[first_is_predictions ? 1 : 0].clone();
  std::size_t instances = 0;
  for (auto _ : state) {
    const auto out = cge::decode_yolov8_seg(predictions, prototypes, lb, settings);
    instances = out.size();
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["instances"] = static_cast<double>(instances);
}
BENCHMARK(BM_Yolov8Decode)->Arg(320)->Arg(640)->Unit(benchmark::kMillisecond);

// ---- PrecomputedMaskReader::read: one 640 x 480 16-bit PNG with the 640 model's instances -------------

void BM_PrecomputedMaskRead(benchmark::State& state) {
  const cv::Mat image = tum_frame();
  if (!std::filesystem::exists(model_path(640)) || image.empty()) {
    state.SkipWithError("../shared models or TUM frame absent");
    return;
  }
  // A mask folder written by this benchmark under a fresh temporary name, removed afterwards.
  const auto dir = std::filesystem::temp_directory_path() /
                   ("cge_bench_masks_" + std::to_string(std::chrono::steady_clock::now().time_since_epoch().count()));
  if (!std::filesystem::create_directory(dir)) {
    state.SkipWithError("cannot create a temporary mask folder");
    return;
  }
  cge::Yolov8Segmenter segmenter(model_path(640));
  const auto instances = segmenter.segment({image, kFrame});
  cv::imwrite((dir / (kFrame + ".png")).string(), cge::instance_label_image(instances, image.size()));
  {
    std::ofstream csv(dir / "instances.csv");
    csv << "id,class_id,class_name,moving\n";
    for (const auto& s : instances)
      csv << s.id << ',' << s.class_id << ',' << cge::coco_class_name(s.class_id) << ",\n";
  }
  {
    const cge::PrecomputedMaskReader reader(dir.string());
    std::size_t read = 0;
    for (auto _ : state) {
      const auto out = reader.read(kFrame, image.size());
      read = out.size();
      benchmark::DoNotOptimize(out.data());
    }
    state.counters["instances"] = static_cast<double>(read);
  }
  std::filesystem::remove_all(dir);
}
BENCHMARK(BM_PrecomputedMaskRead)->Unit(benchmark::kMillisecond);

}  // namespace
