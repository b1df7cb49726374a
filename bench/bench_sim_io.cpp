// The synthetic-sequence output path per frame: the segmentation error model, the PNG encoding of
// one frame's four images (each compression choice), and one frame written to disk. Budget
// (docs/SIMULATION.md): 300 frames in 15 s = 50 ms a frame, of which the renderer takes up to
// 20 ms, leaving ~30 ms for this part. A whole 300-frame sequence is also rendered and written.
//
// The frame imitates a rendered one: a 640 x 480 room of smoothly textured surfaces with a little
// pixel noise, depth from 1 to 4 m with noise growing with the square of the range and holes, two
// people and a chair in the label image.

#include <benchmark/benchmark.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>

#include <unistd.h>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "cge/sim/segmentation_error_model.hpp"
#include "cge/sim/tum_writer.hpp"

#include "cge/sim/presets.hpp"
#include "cge/sim/renderer.hpp"

namespace {

namespace fs = std::filesystem;
using cge::sim::InstanceInfo;

InstanceInfo instance(std::uint16_t id, int class_id, bool moving) {
  InstanceInfo i;
  i.id = id;
  i.class_id = class_id;
  i.moving = moving;
  return i;
}

const std::vector<InstanceInfo>& bench_instances() {
  static const std::vector<InstanceInfo> table = {instance(1, 0, true), instance(2, 0, true), instance(3, 56, false)};
  return table;
}

/// A rendered-looking frame (see the file comment); deterministic.
const cge::sim::RenderedFrame& bench_frame() {
  static const cge::sim::RenderedFrame frame = [] {
    constexpr int kWidth = 640, kHeight = 480;
    constexpr double kUnitsPerMetre = 5000, kNoiseAtOneMetre_m = 0.0015;
    cv::RNG rng(20250707);
    cge::sim::RenderedFrame f;
    f.timestamp_s = 1000;
    cv::Mat texels(kHeight / 4, kWidth / 4, CV_8UC3);
    rng.fill(texels, cv::RNG::UNIFORM, 0, 256);
    cv::resize(texels, f.rgb, cv::Size(kWidth, kHeight), 0, 0, cv::INTER_CUBIC);
    cv::Mat noise(kHeight, kWidth, CV_8UC3);
    rng.fill(noise, cv::RNG::UNIFORM, 0, 6);
    f.rgb += noise;
    f.depth = cv::Mat(kHeight, kWidth, CV_16UC1);
    for (int y = 0; y < kHeight; ++y) {
      for (int x = 0; x < kWidth; ++x) {
        const double z_m = 1.0 + 3.0 * y / kHeight;
        const double noisy_m = z_m + rng.gaussian(kNoiseAtOneMetre_m * z_m * z_m);
        f.depth.at<std::uint16_t>(y, x) = static_cast<std::uint16_t>(std::lround(noisy_m * kUnitsPerMetre));
      }
    }
    f.instance_labels = cv::Mat(kHeight, kWidth, CV_16UC1, cv::Scalar(0));
    cv::ellipse(f.instance_labels, cv::Point(200, 260), cv::Size(55, 190), 0, 0, 360, cv::Scalar(1), cv::FILLED);
    cv::ellipse(f.instance_labels, cv::Point(420, 280), cv::Size(45, 160), 0, 0, 360, cv::Scalar(2), cv::FILLED);
    cv::rectangle(f.instance_labels, cv::Rect(500, 330, 110, 140), cv::Scalar(3), cv::FILLED);
    // No depth on a band around the second person, as at depth discontinuities.
    const cv::Mat person = f.instance_labels == 2;
    cv::Mat grown, shrunk;
    cv::dilate(person, grown, cv::Mat());
    cv::erode(person, shrunk, cv::Mat());
    f.depth.setTo(cv::Scalar(0), grown - shrunk);
    return f;
  }();
  return frame;
}

/// A folder under the temp folder made by this benchmark; removed with its contents at the end.
class BenchDir {
 public:
  BenchDir() {
    static std::atomic<int> counter{0};
    path_ = fs::temp_directory_path() /
            ("cge_bench_sim_io_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
  }
  ~BenchDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  BenchDir(const BenchDir&) = delete;
  BenchDir& operator=(const BenchDir&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// ---- the error model, default settings (erode 2 px, feet, misses, false positives) ----------------

void BM_SimIO_ErrorModel(benchmark::State& state) {
  const cge::sim::SegmentationErrorModel model(bench_instances(), 1);
  const cv::Mat& labels = bench_frame().instance_labels;
  int frame = 0;
  for (auto _ : state) {
    auto r = model.apply(labels, frame);
    benchmark::DoNotOptimize(r.instance_labels.data);
    frame = (frame + 1) % 1000;
  }
}
BENCHMARK(BM_SimIO_ErrorModel)->Unit(benchmark::kMillisecond);

// ---- PNG encoding of one frame's four images: range(0) = png_compression (-1 = fast path) --------

void BM_SimIO_EncodeFrame(benchmark::State& state) {
  const int level = static_cast<int>(state.range(0));
  const cge::sim::SegmentationErrorModel model(bench_instances(), 1);
  const auto segmentation = model.apply(bench_frame().instance_labels, 0);
  std::size_t bytes = 0;
  for (auto _ : state) {
    const auto e = cge::sim::encode_frame(bench_frame(), segmentation, level);
    bytes = e.rgb.size() + e.depth.size() + e.mask.size() + e.segmentation.size();
    benchmark::DoNotOptimize(bytes);
  }
  state.counters["kB_per_frame"] = static_cast<double>(bytes) / 1000.0;
}
BENCHMARK(BM_SimIO_EncodeFrame)->Arg(cge::sim::kPngFast)->Arg(0)->Arg(1)->Arg(3)->Unit(benchmark::kMillisecond);

// ---- one frame through the writer to disk (checks, error model, encoding, four files) -------------

void BM_SimIO_WriteFrame(benchmark::State& state) {
  const BenchDir dir;
  const cge::sim::SegmentationErrorModel model(bench_instances(), 1);
  cge::sim::TumWriterSettings settings;
  settings.force = true;  // the same file names every iteration: overwritten
  const cge::sim::PinholeCamera camera;
  int frame = 0;
  for (auto _ : state) {
    cge::sim::TumSequenceWriter writer(dir.path(), camera, 30, bench_instances(), settings);
    writer.write_frame(bench_frame(), model.apply(bench_frame().instance_labels, frame));
    frame = (frame + 1) % 1000;
  }
}
BENCHMARK(BM_SimIO_WriteFrame)->Unit(benchmark::kMillisecond);

// ---- a whole sequence, rendered and written: the 15 s budget for range(0) = 300 frames ------------

void BM_SimIO_WriteSequence(benchmark::State& state) {
  const int frames = static_cast<int>(state.range(0));
  using Renderer = cge::sim::SequenceRenderer;
  const cge::sim::RendererFrameSource<Renderer> source(Renderer(cge::sim::make_preset("walking_xyz", frames, 1)));
  const cge::sim::SegmentationErrorModel model(source.instances(), 1);
  cge::sim::TumWriterSettings settings;
  settings.force = true;
  const BenchDir dir;
  for (auto _ : state) cge::sim::write_tum_sequence(source, model, dir.path(), settings);
  state.counters["ms_per_frame"] = benchmark::Counter(
      static_cast<double>(frames) * 1e-3, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_SimIO_WriteSequence)->Arg(300)->Unit(benchmark::kSecond)->Iterations(1);

}  // namespace
