// cge_sim: renders a synthetic dynamic RGB-D sequence from a preset and writes it in the TUM
// layout with ground-truth and simulated-network instance masks. See docs/SIMULATION.md.
//
// Standard output: one summary line on success. Standard error: diagnostics, and a progress bar
// when standard error is a terminal (nothing per frame otherwise, so logs stay clean).
// Exit codes: 0 success; 1 the sequence could not be made or written (a file that cannot be
// written, no renderer in this build); 2 bad usage or bad input (unknown preset, zero frames, a
// non-empty output folder without --force, a file of the sequence blocked by a folder of that name
// or the reverse, a setting out of range). A failed run leaves --out as it was (the sequence is
// staged in a hidden folder inside it; a run killed by a signal may leave that folder behind).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstdint>
#include <cstdio>
#include <deque>
#include <exception>
#include <filesystem>
#include <future>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <unistd.h>

#include <CLI/CLI.hpp>

#include "cge/segmentation/coco_classes.hpp"
#include "cge/sim/frame_source.hpp"
#include "cge/sim/segmentation_error_model.hpp"
#include "cge/sim/tum_writer.hpp"

#include "cge/sim/presets.hpp"
#include "cge/sim/renderer.hpp"

#include "tool_support.hpp"

#ifndef CGE_VERSION_STRING
#define CGE_VERSION_STRING "unknown"
#endif

namespace {

using cge_tool::kExitFailure;
using cge_tool::kExitOk;
using cge_tool::kExitUsage;
constexpr const char* kProgram = "cge_sim";
// Frames encoded at the same time while the next one renders: two keep two cores busy when the
// renderer takes less time than an encoding; each frame in flight holds ~3 MB.
constexpr int kFramesInFlight = 2;

cge_tool::ProgressBar progress_bar{kProgram};  // drawn only on a terminal

/// A bad input or flag value, reported on stderr with exit code 2.
using cge_tool::UsageError;

struct Options {
  std::string preset;
  int frames = 0;
  std::uint64_t seed = 0;
  std::string out;
  bool exact_masks = false;
  bool no_depth_noise = false;
  cge::sim::PresetSettings preset_settings;  // --walking-speed, --pause-s
  std::string error_classes = "person";
  cge::sim::SegmentationErrorSettings errors;
  cge::sim::TumWriterSettings writer;
};

// ---- the renderer: the only part of this tool that knows it ------------------------------------

std::vector<std::string> known_presets() { return cge::sim::preset_names(); }

void check_preset(const std::string& name) {
  const std::vector<std::string> names = known_presets();
  if (std::find(names.begin(), names.end(), name) == names.end()) {
    std::string list;
    for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
    throw UsageError("unknown preset '" + name + "' (known presets: " + list + ")");
  }
}

std::unique_ptr<cge::sim::FrameSource> open_preset(const std::string& name, int frames, std::uint64_t seed,
                                                   bool depth_noise, const cge::sim::PresetSettings& settings) {
  using Renderer = cge::sim::SequenceRenderer;
  cge::sim::SequenceSpec spec = cge::sim::make_preset(name, frames, seed, settings);
  spec.render.depth.noise_enabled = depth_noise;
  return std::make_unique<cge::sim::RendererFrameSource<Renderer>>(Renderer(std::move(spec)));
}

// ---- the rest ----------------------------------------------------------------------------------

std::vector<int> parse_classes(const std::string& list, bool& all) {
  all = false;
  std::vector<int> ids;
  std::size_t start = 0;
  while (start <= list.size()) {
    const std::size_t comma = std::min(list.find(',', start), list.size());
    const std::string name = list.substr(start, comma - start);
    start = comma + 1;
    if (name == "all") {
      all = true;
      continue;
    }
    const auto id = cge::coco_class_id(name);
    if (!id) throw UsageError("--error-classes: '" + name + "' is not a COCO class name (e.g. person, chair) or 'all'");
    ids.push_back(*id);
  }
  return ids;
}

/// "[=====>     ]  12/300 frames" on one terminal line, redrawn in place.

/// cge::sim::write_tum_sequence with the PNG encoding, most of a frame's time, on other threads:
/// this thread renders frame i while up to kFramesInFlight earlier frames are being encoded, and
/// commits each frame (checks, files) in frame order once its encoding is done. Encoding is a
/// pure function of the frame and the files are written in order by this thread alone, so the
/// bytes are those of the sequential writer; only the wall time differs. The library itself
/// starts no threads.
void write_overlapped(const cge::sim::FrameSource& source, const cge::sim::SegmentationErrorModel& model,
                      const std::string& out, const cge::sim::TumWriterSettings& settings,
                      const cge::sim::WriteProgress& progress) {
  struct InFlight {
    std::shared_ptr<const cge::sim::SimulatedFrame> frame;
    std::future<cge::sim::EncodedFrame> encoded;
  };
  cge::sim::check_sequence(source, model);
  const int n = source.frame_count();
  const int level = settings.png_compression;
  cge::sim::TumSequenceWriter writer(out, source.camera(), source.frame_rate_hz(), source.instances(), settings);
  std::deque<InFlight> in_flight;  // after the writer: its futures are waited for first
  int committed = 0;
  const auto commit_oldest = [&] {
    InFlight& oldest = in_flight.front();
    writer.write_frame(oldest.frame->frame, oldest.frame->segmentation, oldest.encoded.get());
    in_flight.pop_front();
    if (progress) progress(++committed, n);
  };
  for (int i = 0; i < n; ++i) {
    auto frame = std::make_shared<const cge::sim::SimulatedFrame>(cge::sim::simulate_frame(source, model, i));
    std::future<cge::sim::EncodedFrame> encoded = std::async(std::launch::async, [frame, level] {
      return cge::sim::encode_frame(frame->frame, frame->segmentation, level);
    });
    in_flight.push_back({std::move(frame), std::move(encoded)});
    if (static_cast<int>(in_flight.size()) > kFramesInFlight) commit_oldest();
  }
  while (!in_flight.empty()) commit_oldest();
  writer.finish(source.loops());
}

int run(Options opt) {
  if (opt.frames < 1) throw UsageError("--frames must be at least 1, got " + std::to_string(opt.frames));
  cge_tool::require_at_most("--frames", opt.frames, cge::sim::kMaxPresetFrames, "10 minutes at 30 Hz");
  cge_tool::require_at_most("--walking-speed", opt.preset_settings.walking_speed_mps, cge::sim::kMaxWalkingSpeedMps,
                            "metres per second, a sprinter's");
  if (!opt.exact_masks) {
    cge_tool::require_at_most("--mask-offset-px", std::abs(opt.errors.boundary_offset_px),
                              cge::sim::kMaxBoundaryOffsetPx, "pixels either way");
  }
  if (opt.out.empty()) throw UsageError("--out must name a folder");
  if (opt.exact_masks) {
    opt.errors = cge::sim::exact_segmentation();
  } else {
    opt.errors.affected_class_ids = parse_classes(opt.error_classes, opt.errors.affect_all_classes);
  }
  cge::sim::validate(opt.errors);
  const cge::sim::PresetSettings default_preset;
  opt.writer.description = std::string(kProgram) + " --preset " + opt.preset + " --frames " +
                           std::to_string(opt.frames) + " --seed " + std::to_string(opt.seed) +
                           (opt.no_depth_noise ? " --no-depth-noise" : "");
  // Non-default people motions are part of the sequence's recipe, as the flags that give them.
  if (opt.preset_settings.walking_speed_mps != default_preset.walking_speed_mps)
    opt.writer.description += " --walking-speed " + cge_tool::round_trip_number(opt.preset_settings.walking_speed_mps);
  if (opt.preset_settings.pause_s != default_preset.pause_s)
    opt.writer.description += " --pause-s " + cge_tool::round_trip_number(opt.preset_settings.pause_s);
  check_preset(opt.preset);
  cge::sim::check_output_folder(opt.out, opt.writer.force);

  const auto start = std::chrono::steady_clock::now();
  const auto elapsed_s = [&start] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  const std::unique_ptr<cge::sim::FrameSource> source =
      open_preset(opt.preset, opt.frames, opt.seed, !opt.no_depth_noise, opt.preset_settings);
  const cge::sim::SegmentationErrorModel model(source->instances(), opt.seed, opt.errors);
  cge::sim::WriteProgress progress;
  if (::isatty(::fileno(stderr))) progress = [&](int done, int total) { progress_bar.draw(done, total, elapsed_s()); };
  // All or nothing: the sequence is written into a hidden staging folder inside --out and moved
  // into place only when complete (a failed run leaves --out as it was, the staging folder removed).
  cge_tool::CreatedFolders created;  // --out and its parents when missing: removed again if left empty
  created.create(opt.out, "--out");
  const std::filesystem::path staging =
      std::filesystem::path(opt.out) / (".cge_sim.partial." + std::to_string(::getpid()));
  struct RemoveStaging {
    std::filesystem::path path;
    ~RemoveStaging() {
      std::error_code ec;
      std::filesystem::remove_all(path, ec);
    }
  } remove_staging{staging};
  cge::sim::TumWriterSettings writer = opt.writer;
  writer.force = false;  // the staging folder is new
  write_overlapped(*source, model, staging, writer, progress);
  cge_tool::move_staged_tree(staging, opt.out);

  std::printf("wrote %d frames of %s (seed %llu) to %s in %.1f s\n", source->frame_count(), opt.preset.c_str(),
              static_cast<unsigned long long>(opt.seed), opt.out.c_str(), elapsed_s());
  if (!cge_tool::standard_output_written(kProgram)) return kExitFailure;
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  CLI::App app{"Renders a synthetic dynamic RGB-D sequence (cge " CGE_VERSION_STRING
               ") and writes it in the TUM layout:\nrgb/, depth/, rgb.txt, depth.txt, groundtruth.txt, "
               "camera.yaml, loops.txt, masks/ (ground truth) and\nsegmentation/ (after the segmentation "
               "error model). Same arguments, same bytes. See docs/SIMULATION.md.",
               kProgram};
  app.set_version_flag("--version", std::string(kProgram) + " " + CGE_VERSION_STRING);
  app.add_option("--preset", opt.preset, "scenario, e.g. walking_xyz (--list-presets shows them)")->required();
  app.add_option("--frames", opt.frames,
                 "number of frames, 1 .. " + std::to_string(cge::sim::kMaxPresetFrames))
      ->required();
  app.add_option("--seed", opt.seed, "seed of the scene and of the segmentation errors")
      ->check(cge_tool::seed_check())
      ->capture_default_str();
  app.add_option("--out", opt.out, "output folder; must not exist or be empty, unless --force")->required();
  app.add_flag("--force", opt.writer.force,
               "write into a non-empty folder: overwrite the sequence's own files, delete nothing");
  app.add_option("--png-compression", opt.writer.png_compression,
                 "PNG compression: -1 OpenCV's fast path (default), or a zlib level 0 .. 9 (slower)")
      ->check(CLI::Range(cge::sim::kPngFast, 9))
      ->capture_default_str();
  app.add_flag("--exact-masks", opt.exact_masks, "segmentation/ equal to masks/ (no segmentation errors)");
  app.add_flag("--no-depth-noise", opt.no_depth_noise,
               "depth without the sensor's range noise (still quantised, with its holes and dropouts)");
  app.add_option("--walking-speed", opt.preset_settings.walking_speed_mps,
                 "walking presets: speed of the walking people, metres per second, at most " +
                     cge_tool::round_trip_number(cge::sim::kMaxWalkingSpeedMps))
      ->check(cge_tool::above_zero())
      ->capture_default_str();
  app.add_option("--pause-s", opt.preset_settings.pause_s,
                 "walking presets: how long the second person stands still at each of its stops, seconds")
      ->check(cge_tool::at_least_zero())
      ->capture_default_str();
  app.add_option("--mask-offset-px", opt.errors.boundary_offset_px,
                 "boundary shift of affected masks, pixels: > 0 dilates, < 0 erodes; at most " +
                     std::to_string(cge::sim::kMaxBoundaryOffsetPx) + " either way")
      ->capture_default_str();
  app.add_option("--feet-probability", opt.errors.feet_loss_probability,
                 "probability per instance and frame that the feet are lost")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app.add_option("--feet-fraction", opt.errors.feet_loss_fraction,
                 "fraction of the mask height removed at the bottom when the feet are lost")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app.add_option("--miss-probability", opt.errors.miss_probability,
                 "probability per instance and frame that an instance is missed")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app.add_option("--false-positive-probability", opt.errors.false_positive_probability,
                 "probability per frame of one false-positive blob")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app.add_option("--error-classes", opt.error_classes,
                 "comma-separated COCO class names that receive the errors, or 'all'")
      ->capture_default_str();
  // --list-presets works without the other options: it is handled as a callback that exits.
  app.add_flag_callback(
      "--list-presets",
      [] {
        for (const std::string& n : known_presets()) std::printf("%s\n", n.c_str());
        throw CLI::Success();
      },
      "print the preset names and exit");

  // CLI::Success from --list-presets is a parse "error" with exit code 0: parse_command_line
  // returns 0 for it.
  if (const int code = cge_tool::parse_command_line(app, argc, argv, kProgram); code >= 0) return code;

  return cge_tool::run_reporting_errors(kProgram, &progress_bar, [&] { return run(opt); });
}
