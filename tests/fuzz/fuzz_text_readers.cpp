// Fuzz harness of the toolkit's text readers: the first byte of an input picks the reader, the
// rest is the text. A reader may refuse its input only with std::invalid_argument (cge::ParseError
// derives from it); anything else escaping, a sanitizer report, or a broken check below is a
// finding. Where a reader accepts, the harness also runs what a tool would run next and checks
// one property of the result that must hold whatever the input:
//   0 edge list -> degree-degree entropy and edge entropy, finite
//   1 edge list with one-based ids
//   2 point list -> GraphBuilder on a 640 x 480 image, the same graph with the grid and the
//     brute-force neighbour search -> degree-degree entropy, finite
//   3 TUM trajectory -> ATE of the trajectory against itself, zero
//   4 ground-truth loops, 5 loops.csv queries, 6 vocabulary, 7 TUM image list
//   8 TUM trajectory keeping the later of two lines with one timestamp (cge_eval's default)
//   and, when built with OpenCV (CGE_FUZZ_HAS_OPENCV):
//   9 ORB-SLAM2 settings YAML (read_orbslam2_settings reads a file: the text goes to a temporary
//     file of this process first) -> bounded ORB settings whose pyramid fits Camera.width x height
//   10 instances.csv of a precomputed mask folder -> ids in 1 .. 65535, classes in 0 .. 79
// CGE_FUZZ_READER=<k> in the environment pins every input to reader k (docs/CLI.md has the runs).
// Built two ways (tests/fuzz/CMakeLists.txt): with libFuzzer when CGE_BUILD_FUZZERS is on (Clang),
// and always as cge_fuzz_replay, which ctest runs over tests/fuzz/corpus.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <stdexcept>
#include <string>

#include "cge/bow/vocabulary.hpp"
#include "cge/dataset/tum_list.hpp"
#include "cge/entropy/degree_degree_entropy.hpp"
#include "cge/entropy/shannon_edge_entropy.hpp"
#include "cge/graph/graph_builder.hpp"
#include "cge/io/graph_text.hpp"
#include "cge/metrics/ate.hpp"
#include "cge/metrics/ground_truth_loops_io.hpp"
#include "cge/metrics/loop_queries_io.hpp"
#include "cge/metrics/tum_trajectory_io.hpp"

#ifdef CGE_FUZZ_HAS_OPENCV
#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "cge/dataset/orbslam2_settings.hpp"
#include "cge/segmentation/precomputed_mask_reader.hpp"
#endif

namespace {

// Entropy inputs stay small, so that one input runs in milliseconds.
constexpr std::int32_t kMaxVertices = 200;
constexpr std::int32_t kMaxEntropyNodes = 300;

void require(bool ok, const char* what) {
  if (ok) return;
  std::fprintf(stderr, "fuzz_text_readers: property broken: %s\n", what);
  std::abort();
}

void entropies_are_finite(const cge::Graph<double>& g) {
  if (g.num_nodes() == 0 || g.num_nodes() > kMaxEntropyNodes) return;
  const auto r = cge::DegreeDegreeEntropy<double>{}.compute(g);
  require(std::isfinite(r.entropy_bits) && std::isfinite(r.information_index), "degree-degree entropy is finite");
  require(std::isfinite(cge::ShannonEdgeEntropy<double>{}.compute(g)), "edge entropy is finite");
}

void run(int reader, std::istream& in) {
  switch (reader) {
    case 0:
    case 1: {
      cge::io::EdgeListOptions options;
      options.one_based = reader == 1;
      options.max_vertices = kMaxVertices;
      entropies_are_finite(cge::io::read_edge_list(in, "fuzz", options));
      break;
    }
    case 2: {
      const cge::io::PointList list = cge::io::read_point_list(in, "fuzz");
      cge::ImageRegion<double> image;
      image.width_px = 640;
      image.height_px = 480;
      const cge::Graph<double> g = cge::GraphBuilder<double>{}.build(image, list.points, list.instances);
      const cge::Graph<double> reference =
          cge::GraphBuilder<double, cge::BruteForceNeighborSearch<double>>{}.build(image, list.points, list.instances);
      require(g == reference, "the grid and brute-force neighbour searches build the same graph");
      entropies_are_finite(g);
      break;
    }
    case 3: {
      const cge::metrics::Trajectory t = cge::metrics::read_tum_trajectory(in, "fuzz");
      if (t.empty()) break;
      require(cge::metrics::compute_ate(t, t).translation_m.rmse < 1e-6, "ATE of a trajectory against itself is 0");
      break;
    }
    case 4:
      (void)cge::metrics::read_ground_truth_loops(in, "fuzz");
      break;
    case 5:
      (void)cge::metrics::read_loop_queries(in, "fuzz");
      break;
    case 6:
      (void)cge::bow::Vocabulary::load(in, "fuzz");
      break;
    case 7:
      (void)cge::dataset::parse_tum_list(in, "fuzz");
      break;
    case 8: {
      cge::metrics::TumReadSettings settings;
      settings.duplicate_timestamps = cge::metrics::DuplicateTimestamps::keep_last;
      const cge::metrics::Trajectory t = cge::metrics::read_tum_trajectory(in, "fuzz", settings);
      for (std::size_t i = 1; i < t.size(); ++i) {
        require(t[i - 1].timestamp_s < t[i].timestamp_s, "kept timestamps strictly increase");
      }
      break;
    }
#ifdef CGE_FUZZ_HAS_OPENCV
    case 9: {
      static const std::filesystem::path file =
          std::filesystem::temp_directory_path() / ("cge_fuzz_settings." + std::to_string(::getpid()) + ".yaml");
      {
        std::ofstream out(file, std::ios::binary | std::ios::trunc);
        out << in.rdbuf();
      }
      const cge::dataset::OrbSlam2Settings s = cge::dataset::read_orbslam2_settings(file);
      require(s.camera.fx_px > 0 && s.camera.fy_px > 0 && s.depth_map_factor > 0, "accepted intrinsics are positive");
      require(s.orb.levels <= cge::dataset::kMaxOrbLevels && s.orb.features <= cge::dataset::kMaxOrbFeatures,
              "accepted ORB settings are bounded");
      require(s.width_px == 0 || cge::dataset::coarsest_level_fits(s.orb, s.width_px, s.height_px),
              "an accepted pyramid fits the camera's image");
      break;
    }
    case 10: {
      for (const auto& [id, instance] : cge::read_instances_csv(in, "fuzz")) {
        require(id == instance.id && id >= 1 && id <= 65535, "instance ids lie in 1 .. 65535");
        require(instance.class_id >= 0 && instance.class_id <= 79, "class ids lie in 0 .. 79");
      }
      break;
    }
#endif
    default:
      break;
  }
}

constexpr int kReaders = 11;

/// CGE_FUZZ_READER=<k> pins every input to reader k (its first byte is then ignored), so that each
/// reader gets its own run of a given length; -1 (unset): the first byte picks.
int pinned_reader() {
  static const int reader = [] {
    const char* text = std::getenv("CGE_FUZZ_READER");
    if (text == nullptr || *text == '\0') return -1;
    const int k = std::atoi(text);
    return k >= 0 && k < kReaders ? k : -1;
  }();
  return reader;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  std::istringstream in(std::string(reinterpret_cast<const char*>(data) + 1, size - 1));
  try {
    run(pinned_reader() >= 0 ? pinned_reader() : data[0] % kReaders, in);
  } catch (const std::invalid_argument&) {
    // the reader refused the input: the expected outcome for most inputs
  }
  return 0;
}
