// Semantic maps (cge/mapping/semantic_map_builder.hpp): building the cloud and the 5 cm octree from
// keyframes of a rendered walking_xyz sequence (640 x 480, ground-truth poses, exact masks).
// Target: under 50 ms per keyframe. The octree's memory is reported as a counter.

#include <benchmark/benchmark.h>

#include <cstdint>
#include <map>
#include <vector>

#include "cge/mapping/semantic_map_builder.hpp"
#include "cge/voxels/voxel_filter.hpp"
#include "cge/sim/presets.hpp"
#include "cge/sim/renderer.hpp"

namespace {

constexpr int kFrames = 300;
constexpr int kKeyframeStep = 10;  // 30 keyframes over 10 s

struct Data {
  cge::PinholeIntrinsics<double> intrinsics;
  std::vector<cge::slam::Keyframe> keyframes;
};

const Data& data() {
  static const Data d = [] {
    Data out;
    const cge::sim::SequenceRenderer renderer(cge::sim::make_preset("walking_xyz", kFrames, 1));
    const cge::sim::PinholeCamera& c = renderer.camera();
    out.intrinsics.fx_px = c.fx_px;
    out.intrinsics.fy_px = c.fy_px;
    out.intrinsics.cx_px = c.cx_px;
    out.intrinsics.cy_px = c.cy_px;
    std::map<std::uint16_t, cge::sim::InstanceInfo> by_id;
    for (const auto& i : renderer.instances()) by_id[i.id] = i;
    for (int i = 0; i < kFrames; i += kKeyframeStep) {
      const cge::sim::RenderedFrame f = renderer.render(i);
      cge::slam::Keyframe kf;
      kf.id = static_cast<int>(out.keyframes.size());
      kf.frame_index = i;
      kf.T_world_camera = f.T_world_camera;
      kf.bgr = f.rgb;
      f.depth.convertTo(kf.depth_m, CV_32F, 1.0 / c.depth_units_per_metre);
      kf.class_labels = cv::Mat(f.instance_labels.size(), CV_16UC1, cv::Scalar(0));
      kf.dynamic_mask = cv::Mat(f.instance_labels.size(), CV_8UC1, cv::Scalar(0));
      for (int v = 0; v < f.instance_labels.rows; ++v)
        for (int u = 0; u < f.instance_labels.cols; ++u) {
          const std::uint16_t id = f.instance_labels.at<std::uint16_t>(v, u);
          if (id == 0) continue;
          kf.class_labels.at<std::uint16_t>(v, u) = static_cast<std::uint16_t>(by_id.at(id).class_id + 1);
          if (by_id.at(id).moving) kf.dynamic_mask.at<std::uint8_t>(v, u) = 255;
        }
      out.keyframes.push_back(kf);
    }
    return out;
  }();
  return d;
}

/// rebuild() of the whole map (cloud and octree) from the keyframes; the counters give the time per
/// keyframe and the octree's memory at the end. Arg: the octree's pixel stride.
void BM_MapsRebuild(benchmark::State& state) {
  const Data& d = data();
  cge::mapping::SemanticMapSettings settings;
  settings.octree_pixel_stride = static_cast<int>(state.range(0));  // the cloud keeps stride 2
  cge::mapping::SemanticMapBuilder builder(d.intrinsics, settings);
  for (auto _ : state) {
    builder.rebuild(d.keyframes);
    benchmark::DoNotOptimize(builder.entities().data());
  }
  const double n = static_cast<double>(d.keyframes.size());
  state.counters["s_per_keyframe"] =
      benchmark::Counter(n, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["octree_MiB"] = static_cast<double>(builder.octree().memory_bytes()) / (1024.0 * 1024.0);
  state.counters["tree_MiB"] = static_cast<double>(builder.octree().tree_memory_bytes()) / (1024.0 * 1024.0);
  state.counters["occupied_voxels"] = static_cast<double>(builder.occupied_voxels().voxels.size());
}
BENCHMARK(BM_MapsRebuild)->Arg(2)->Arg(4)->Arg(8)->Unit(benchmark::kMillisecond);

/// rebuild() at the default strides with the octree's free-space carving at one ray per block of
/// n^3 end voxels. Arg: ray_block_voxels (1 = a ray to every end voxel, OctoMap's insertPointCloud).
void BM_MapsRebuildRayBlock(benchmark::State& state) {
  const Data& d = data();
  cge::mapping::SemanticMapSettings settings;
  settings.octree.ray_block_voxels = static_cast<int>(state.range(0));
  cge::mapping::SemanticMapBuilder builder(d.intrinsics, settings);
  for (auto _ : state) {
    builder.rebuild(d.keyframes);
    benchmark::DoNotOptimize(builder.entities().data());
  }
  state.counters["s_per_keyframe"] =
      benchmark::Counter(static_cast<double>(d.keyframes.size()),
                         benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_MapsRebuildRayBlock)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

/// The cloud's share of insert(): back-projection at stride 2 and the per-keyframe voxel filter.
void BM_MapsCloudPart(benchmark::State& state) {
  const Data& d = data();
  const cge::mapping::SemanticMapBuilder builder(d.intrinsics);
  for (auto _ : state) {
    for (const cge::slam::Keyframe& kf : d.keyframes) {
      benchmark::DoNotOptimize(
          cge::mapping::voxel_filter(builder.keyframe_points(kf), builder.settings().cloud_voxel_m).size());
    }
  }
  state.counters["s_per_keyframe"] =
      benchmark::Counter(static_cast<double>(d.keyframes.size()),
                         benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_MapsCloudPart)->Unit(benchmark::kMillisecond);

/// The final products: the voxel-filtered cloud over all keyframes and the occupied voxels.
void BM_MapsCloudAndVoxels(benchmark::State& state) {
  const Data& d = data();
  cge::mapping::SemanticMapBuilder builder(d.intrinsics);
  builder.rebuild(d.keyframes);
  for (auto _ : state) {
    benchmark::DoNotOptimize(builder.cloud().size());
    benchmark::DoNotOptimize(builder.occupied_voxels().voxels.size());
  }
}
BENCHMARK(BM_MapsCloudAndVoxels)->Unit(benchmark::kMillisecond);

}  // namespace
