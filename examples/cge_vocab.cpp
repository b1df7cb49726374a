// cge_vocab: trains a bag-of-words vocabulary for ORB descriptors (cge::bow::Vocabulary) from a
// folder of images, a list file (one image path per line, or a TUM rgb.txt: "timestamp path"), or
// a synthetic sequence rendered in memory, and writes it in the text format of
// docs/LOOP_CLOSING.md. Same arguments, same file.
//
// --out is written beside its name and renamed into place when complete; missing folders on the way
// are created (docs/CLI.md). Exit codes: 0 done, 2 bad arguments or input (nothing written), 1
// other failure.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <opencv2/imgcodecs.hpp>

#include "cge/dataset/orbslam2_settings.hpp"
#include "cge/io/stderr_capture.hpp"
#include "cge/sim/frame_source.hpp"
#include "cge/sim/presets.hpp"
#include "cge/sim/renderer.hpp"
#include "cge/slam/vocabulary_training.hpp"
#include "tool_support.hpp"

namespace fs = std::filesystem;

namespace {

constexpr const char* kProgram = "cge_vocab";
using cge_tool::kExitOk;

struct Options {
  std::string images_dir;
  std::string list_file;
  std::string preset;
  int preset_frames = 30;
  std::uint64_t preset_seed = 1;
  std::string out;
  bool force = false;
  int step = 1;
  int max_images = 0;
  cge::slam::VocabularyTrainingSettings training;
};

bool is_image_name(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp" || ext == ".ppm" || ext == ".pgm" ||
         ext == ".tif" || ext == ".tiff";
}

std::vector<std::string> images_in_folder(const std::string& dir) {
  if (!fs::is_directory(dir)) throw std::invalid_argument("--images: " + dir + " is not a folder");
  std::vector<std::string> paths;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.is_regular_file() && is_image_name(e.path())) paths.push_back(e.path().string());
  }
  std::sort(paths.begin(), paths.end());
  if (paths.empty()) throw std::invalid_argument("--images: no image files (png, jpg, bmp, ppm, pgm, tif) in " + dir);
  return paths;
}

/// One path per line, or "timestamp path" (TUM rgb.txt); '#' starts a comment line; relative paths
/// are relative to the list file's folder.
std::vector<std::string> images_in_list(const std::string& file) {
  std::error_code ec;
  if (fs::is_directory(file, ec)) throw std::invalid_argument("--list: " + file + " is a directory, not a file");
  std::ifstream in(file);
  if (!in) throw std::invalid_argument("--list: cannot open " + file);
  const fs::path base = fs::path(file).parent_path();
  std::vector<std::string> paths;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const auto first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream fields(line);
    std::vector<std::string> tokens;
    for (std::string t; fields >> t;) tokens.push_back(t);
    if (tokens.size() > 2) {
      throw std::invalid_argument(file + ":" + std::to_string(line_no) +
                                  ": expected \"path\" or \"timestamp path\", found " + std::to_string(tokens.size()) +
                                  " fields");
    }
    const fs::path p = tokens.back();
    paths.push_back((p.is_absolute() ? p : base / p).string());
  }
  if (paths.empty()) throw std::invalid_argument("--list: " + file + " lists no images");
  return paths;
}

int run(const Options& opt) {
  const int sources = (opt.images_dir.empty() ? 0 : 1) + (opt.list_file.empty() ? 0 : 1) + (opt.preset.empty() ? 0 : 1);
  if (sources != 1) throw std::invalid_argument("give exactly one of --images, --list, --preset");
  cge_tool::check_output_file(opt.out, "--out", opt.force);
  if (!opt.preset.empty()) {
    if (opt.preset_frames < 1) {
      throw cge_tool::UsageError("--frames must be at least 1, got " + std::to_string(opt.preset_frames));
    }
    cge_tool::require_at_most("--frames", opt.preset_frames, cge::sim::kMaxPresetFrames, "10 minutes at 30 Hz");
  }
  cge_tool::require_at_most("--features", opt.training.orb_features, cge::dataset::kMaxOrbFeatures,
                            "the ORB extractor reserves memory per feature");
  opt.training.vocabulary.validate();

  // Images are turned into descriptors one at a time, so memory grows with the descriptors (the
  // training's input), not with the images.
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::vector<cge::bow::BinaryDescriptor>> documents;
  std::size_t descriptors = 0;
  const auto add_image = [&](const cv::Mat& image) {
    documents.push_back(cge::slam::orb_descriptors(image, opt.training.orb_features));
    descriptors += documents.back().size();
  };
  const auto full = [&] { return opt.max_images > 0 && static_cast<int>(documents.size()) >= opt.max_images; };
  std::string source;
  if (!opt.preset.empty()) {
    const cge::sim::SequenceRenderer renderer(cge::sim::make_preset(opt.preset, opt.preset_frames, opt.preset_seed));
    for (int i = 0; i < renderer.frame_count() && !full(); i += opt.step) add_image(renderer.render(i).rgb);
    source = "preset " + opt.preset + " (" + std::to_string(opt.preset_frames) + " frames, seed " +
             std::to_string(opt.preset_seed) + ")";
  } else {
    const std::vector<std::string> paths =
        opt.images_dir.empty() ? images_in_list(opt.list_file) : images_in_folder(opt.images_dir);
    for (std::size_t i = 0; i < paths.size() && !full(); i += static_cast<std::size_t>(opt.step)) {
      std::error_code ec;
      if (fs::is_directory(paths[i], ec)) throw std::invalid_argument("the image " + paths[i] + " is a directory");
      cge::io::StderrCapture decoder_messages;  // libpng's complaints join the message below
      const cv::Mat img = cv::imread(paths[i], cv::IMREAD_COLOR);
      const std::string said = decoder_messages.finish();
      if (img.empty()) {
        throw std::invalid_argument("cannot read the image " + paths[i] + (said.empty() ? "" : " (" + said + ")"));
      }
      add_image(img);
    }
    source = opt.images_dir.empty() ? opt.list_file : opt.images_dir;
  }

  const cge::bow::Vocabulary v = cge::slam::train_vocabulary_from_descriptors(documents, opt.training);
  cge_tool::CreatedFolders folders;
  folders.create_parent_of(opt.out, "--out");
  cge_tool::replace_file_with_stream(opt.out, [&v](std::ostream& f) { v.save(f); });
  folders.keep();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  std::printf("source %s\n", source.c_str());
  std::printf("images %zu\n", documents.size());
  std::printf("descriptors %zu\n", descriptors);
  std::printf("branching %d\ndepth %d\nseed %llu\n", v.branching(), v.depth(),
              static_cast<unsigned long long>(opt.training.seed));
  std::printf("nodes %zu\nwords %zu\n", v.node_count(), v.word_count());
  std::printf("seconds %.2f\n", seconds);
  std::printf("output %s\n", opt.out.c_str());
  if (!cge_tool::standard_output_written(kProgram)) return cge_tool::kExitFailure;
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  CLI::App app{"Trains a bag-of-words vocabulary for ORB descriptors (cge " CGE_VERSION_STRING
               ") and writes it in the text format of docs/LOOP_CLOSING.md. Same arguments, same file.",
               kProgram};
  app.set_version_flag("--version", std::string(kProgram) + " " + CGE_VERSION_STRING);
  app.add_option("--images", opt.images_dir, "folder of images (png, jpg, bmp, ppm, pgm, tif), used in name order");
  app.add_option("--list", opt.list_file, "list file: one image path per line, or a TUM rgb.txt");
  app.add_option("--preset", opt.preset, "render this synthetic preset in memory instead (e.g. walking_xyz)");
  app.add_option("--frames", opt.preset_frames, "--preset: frames to render, 1 .. " + std::to_string(cge::sim::kMaxPresetFrames))->capture_default_str();
  app.add_option("--preset-seed", opt.preset_seed, "--preset: the scene's seed")
      ->check(cge_tool::seed_check())
      ->capture_default_str();
  app.add_option("--out", opt.out, "vocabulary file to write; an existing file only with --force")->required();
  app.add_flag("--force", opt.force, "overwrite --out when it exists");
  app.add_option("--features", opt.training.orb_features, "ORB features per image, >= 1")
      ->check(cge_tool::above_zero())
      ->capture_default_str();
  app.add_option("--branching,-k", opt.training.vocabulary.branching, "children per node k, >= 2")
      ->check(CLI::Range(2, 1000))
      ->capture_default_str();
  app.add_option("--depth,-L", opt.training.vocabulary.depth, "levels below the root L, >= 1")
      ->check(CLI::Range(1, 16))
      ->capture_default_str();
  app.add_option("--iterations", opt.training.vocabulary.max_iterations, "k-medians rounds per node at most")
      ->check(cge_tool::above_zero())
      ->capture_default_str();
  app.add_option("--seed", opt.training.seed, "seed of the k-means++ draws")
      ->check(cge_tool::seed_check())
      ->capture_default_str();
  app.add_option("--step", opt.step, "use every step-th image, >= 1")
      ->check(cge_tool::above_zero())
      ->capture_default_str();
  app.add_option("--max-images", opt.max_images, "use at most this many images (0: all)")
      ->check(cge_tool::at_least_zero())
      ->capture_default_str();
  if (const int exit_code = cge_tool::parse_command_line(app, argc, argv, kProgram); exit_code >= 0) return exit_code;
  return cge_tool::run_reporting_errors(kProgram, nullptr, [&] { return run(opt); });
}
