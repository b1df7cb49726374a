// The recipe of cge_loop_study (examples/cge_loop_study.cpp) against the LoopCloser itself: for
// every decision with a match on a short rendered loop sequence, S_sum computed the study's way
// (own_mask_graph, one Delta table per frame, from_table for the scaling, combine) equals the
// LoopCloser's cge_score bit for bit, with raw and with normalised exponents and another alpha.

#include <catch2/catch.hpp>

#include <vector>

#include "cge/entropy/shortest_path_degree_sums.hpp"
#include "cge/sim/presets.hpp"
#include "cge/sim/renderer.hpp"
#include "cge/slam/loop_closer.hpp"
#include "cge/slam/vocabulary_training.hpp"
#include "loop_test_support.hpp"

namespace {

cge::GraphEntropies<double> study_entropies(const cge::slam::Keyframe& kf, const cge::CGESimilarity<double>& sim,
                                            const cge::ImageRegion<double>& image) {
  const cge::Graph<double> g = cge::slam::own_mask_graph(kf, image, sim.graph_builder);
  REQUIRE(g.num_nodes() > 0);
  const cge::DegreeSumTable table = cge::shortest_path_degree_sums(g, sim.degree_entropy.settings.ties);
  return {sim.degree_entropy.from_table(table).information_index, sim.edge_entropy.compute(g), g.num_nodes(),
          g.num_edges()};
}

}  // namespace

TEST_CASE("cge_loop_study's recipe gives the LoopCloser's S_sum", "[loop_study][loop]") {
  const cge::sim::SequenceSpec spec =
      cge::sim::make_preset("loop_dynamic", 40, 5, cge::sim::repeated_room_loop_settings(2));
  const cge::sim::SequenceRenderer renderer(spec);
  std::vector<cge::slam::Keyframe> keyframes;
  std::vector<cv::Mat> images;
  for (int i = 0; i < renderer.frame_count(); ++i) {
    const cge::sim::RenderedFrame f = renderer.render(i);
    keyframes.push_back(cge_test::keyframe_from_frame(f, spec.camera, spec.instances, i));
    images.push_back(f.rgb);
  }
  const cge::bow::Vocabulary vocabulary =
      cge::slam::train_vocabulary(std::vector<cv::Mat>(images.begin(), images.begin() + 10));
  cge::ImageRegion<double> image;
  image.width_px = spec.camera.width_px;
  image.height_px = spec.camera.height_px;

  for (const cge::ScalingKind scaling : {cge::ScalingKind::raw, cge::ScalingKind::normalised_mean}) {
    for (const double alpha : {0.5, 0.8}) {
      cge::slam::LoopCloserSettings settings;
      settings.exponent_scaling = scaling;
      settings.degree_entropy.alpha = alpha;
      settings.scoring = cge::slam::LoopScoring::cge;
      cge::slam::LoopCloser closer(vocabulary, cge_test::intrinsics_of(spec.camera), spec.camera.width_px,
                                   spec.camera.height_px, settings);
      const cge::CGESimilarity<double> sim = cge::slam::loop_similarity(settings);
      cge_test::PoseCovisibilityView view(keyframes, 5, 60.0);
      int compared = 0;
      for (const cge::slam::Keyframe& kf : keyframes) {
        view.set_count(kf.id + 1);
        const cge::slam::LoopDecision d = closer.process(kf, view);
        if (d.match_keyframe < 0) continue;
        const cge::slam::Keyframe& match = keyframes[static_cast<std::size_t>(d.match_keyframe)];
        const double s_sum = sim.combine(study_entropies(kf, sim, image), study_entropies(match, sim, image),
                                         cge::compare_semantics(kf.instances, match.instances))
                                 .similarity;
        INFO("scaling " << static_cast<int>(scaling) << " alpha " << alpha << " query " << kf.id << " match "
                        << d.match_keyframe);
        CHECK(s_sum == d.cge_score);
        ++compared;
      }
      CHECK(compared >= 5);
    }
  }
}
