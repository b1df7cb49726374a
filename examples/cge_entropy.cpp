// cge_entropy: the degree-degree association entropy, information index and edge entropy of one
// graph, read from an edge list or built from a point list. See docs/CLI.md.
//
// Output: one "name value" line per quantity on standard output (values with 15 significant
// digits), diagnostics on standard error. The graph is bounded before the work (--max-vertices:
// the largest vertex id + 1, or the number of points); a computation expected to take long says
// so on standard error, and on a terminal shows the elapsed time while it runs. Exit codes: 0 success; 1 a computation that cannot be
// carried out (path multiplicities overflowing double); 2 bad usage or bad input.

#include <cerrno>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <mutex>
#include <stdexcept>
#include <string>
#include <system_error>
#include <thread>

#include <unistd.h>

#include <CLI/CLI.hpp>

#include "cge/entropy/coefficients.hpp"
#include "cge/entropy/degree_degree_entropy.hpp"
#include "cge/entropy/exponent_scaling.hpp"
#include "cge/entropy/shannon_edge_entropy.hpp"
#include "cge/entropy/shortest_path_degree_sums.hpp"
#include "cge/graph/graph_builder.hpp"
#include "cge/io/graph_text.hpp"

#include "tool_support.hpp"

#ifndef CGE_VERSION_STRING
#define CGE_VERSION_STRING "unknown"
#endif

namespace {

constexpr int kExitOk = 0;
constexpr int kExitComputation = 1;
constexpr int kExitUsage = 2;
constexpr const char* kProgram = "cge_entropy";

/// A bad input or flag value, reported on stderr with exit code 2.
using cge_tool::UsageError;

struct Options {
  std::string file = "-";
  bool points = false;
  bool one_based = false;
  double alpha = 0.5;
  double lambda = 1.0;
  cge::CoefficientKind coeff = cge::CoefficientKind::exp;
  cge::TieMode ties = cge::TieMode::all;
  cge::ScalingKind scaling = cge::ScalingKind::raw;
  double width_px = 640.0;
  double height_px = 480.0;
  int dense_threshold = cge::GraphBuilderSettings<double>().dense_patch_threshold;
  double radius_fraction = cge::GraphBuilderSettings<double>().radius_fraction_of_diagonal;
  /// Largest accepted number of vertices. The search allocates and loops per vertex, isolated ones
  /// included (an edge list has max id + 1 vertices): 2^20 keeps a graph of isolated ids within
  /// ~100 MB and seconds, while real frame graphs have hundreds of nodes.
  std::int32_t max_vertices = std::int32_t(1) << 20;
};

/// Searches above this many steps (|V| (|V| + |E|), one breadth-first search per vertex) get a
/// note on standard error: on this kind of machine they run for a minute or more.
constexpr double kLongWorkSteps = 1e10;

/// On a terminal, "cge_entropy: computing ... 12 s" redrawn every second while the search runs
/// (the library call has no progress hook; this thread only prints).
class ElapsedTicker {
 public:
  explicit ElapsedTicker(std::string what) {
    if (::isatty(::fileno(stderr)) == 0) return;
    thread_ = std::thread([this, what = std::move(what)] {
      const auto start = std::chrono::steady_clock::now();
      std::unique_lock<std::mutex> lock(mutex_);
      while (!cv_.wait_for(lock, std::chrono::seconds(1), [this] { return done_; })) {
        const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::fprintf(stderr, "\r%s: %s ... %.0f s", kProgram, what.c_str(), s);
        std::fflush(stderr);
        drawn_ = true;
      }
      if (drawn_) std::fputc('\n', stderr);
    });
  }
  ElapsedTicker(const ElapsedTicker&) = delete;
  ElapsedTicker& operator=(const ElapsedTicker&) = delete;
  ~ElapsedTicker() {
    if (!thread_.joinable()) return;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      done_ = true;
    }
    cv_.notify_one();
    thread_.join();
  }

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  bool done_ = false;
  bool drawn_ = false;
  std::thread thread_;
};

std::string number(double value) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.15g", value);
  return buf;
}

void require_positive(const char* flag, double value) {
  if (!(std::isfinite(value) && value > 0)) {
    throw UsageError(std::string(flag) + " must be a finite positive number, got " + number(value));
  }
}

void print_value(const char* name, double value) { std::printf("%s %.15g\n", name, value); }

cge::Graph<double> read_points_graph(std::istream& in, const std::string& source, const Options& opt) {
  const cge::io::PointList list = cge::io::read_point_list(in, source);
  const std::size_t nodes = list.points.size() + list.instances.size();
  if (nodes > static_cast<std::size_t>(opt.max_vertices)) {
    throw UsageError(source + ": " + std::to_string(nodes) + " points exceed --max-vertices " +
                     std::to_string(opt.max_vertices));
  }
  cge::ImageRegion<double> image;
  image.width_px = opt.width_px;
  image.height_px = opt.height_px;
  // Check the region here, where the line of every point is known.
  for (std::size_t i = 0; i < list.points.size(); ++i) {
    if (!image.contains(list.points[i])) {
      throw cge::io::ParseError(source, list.point_lines[i],
                                "point lies outside the " + number(opt.width_px) + " x " + number(opt.height_px) +
                                    " image (see --width, --height)");
    }
  }
  for (std::size_t i = 0; i < list.instances.size(); ++i) {
    if (!image.contains(list.instances[i].centre_px)) {
      throw cge::io::ParseError(source, list.instance_lines[i],
                                "semantic centre lies outside the " + number(opt.width_px) + " x " +
                                    number(opt.height_px) + " image (see --width, --height)");
    }
  }
  cge::GraphBuilder<double> builder;
  builder.settings.dense_patch_threshold = opt.dense_threshold;
  builder.settings.radius_fraction_of_diagonal = opt.radius_fraction;
  return builder.build(image, list.points, list.instances);
}

int run(const Options& opt) {
  require_positive("--alpha", opt.alpha);
  require_positive("--lambda", opt.lambda);
  if (opt.max_vertices < 1) throw UsageError("--max-vertices must be at least 1");
  if (opt.points) {
    require_positive("--width", opt.width_px);
    require_positive("--height", opt.height_px);
    require_positive("--radius-fraction", opt.radius_fraction);
    if (opt.dense_threshold < 0) throw UsageError("--dense-threshold must not be negative");
  }

  const bool from_stdin = opt.file == "-";
  const std::string source = from_stdin ? "<stdin>" : opt.file;
  std::ifstream file;
  if (!from_stdin) {
    std::error_code ec;
    if (std::filesystem::is_directory(opt.file, ec))
      throw UsageError("cannot read '" + opt.file + "': it is a directory");
    errno = 0;
    file.open(opt.file);
    if (!file) {
      const int err = errno;
      throw UsageError("cannot open '" + opt.file + "'" + (err != 0 ? std::string(": ") + std::strerror(err) : ""));
    }
  }
  std::istream& in = from_stdin ? std::cin : file;

  cge::Graph<double> g;
  if (opt.points) {
    g = read_points_graph(in, source, opt);
    if (g.num_nodes() == 0) throw UsageError(source + ": the point list contains no points");
  } else {
    cge::io::EdgeListOptions eo;
    eo.one_based = opt.one_based;
    eo.max_vertices = opt.max_vertices;
    eo.max_vertices_name = "--max-vertices";
    g = cge::io::read_edge_list(in, source, eo);
    if (g.num_nodes() == 0) throw UsageError(source + ": the edge list contains no edges");
  }

  cge::DegreeDegreeEntropy<double> dde;
  dde.settings.alpha = opt.alpha;
  dde.settings.lambda = opt.lambda;
  dde.settings.ties = opt.ties;
  dde.coefficients.kind = opt.coeff;
  dde.scaling.kind = opt.scaling;
  const double vertices = g.num_nodes();
  const double steps = vertices * (vertices + static_cast<double>(g.num_edges()));
  if (steps > kLongWorkSteps) {
    std::fprintf(stderr,
                 "%s: note: %d vertices and %d edges: one breadth-first search per vertex (%.2g steps); this may "
                 "take minutes\n",
                 kProgram, g.num_nodes(), g.num_edges(), steps);
  }
  const auto r = [&] {
    const ElapsedTicker ticker("computing the degree sums of " + std::to_string(g.num_nodes()) + " vertices");
    return dde.compute(g);
  }();
  if (!r.connected) {
    std::fprintf(stderr,
                 "%s: note: the graph is not connected; the diameter is the largest finite distance and "
                 "unreachable pairs are ignored\n",
                 kProgram);
  }

  print_value("vertices", g.num_nodes());
  print_value("edges", g.num_edges());
  print_value("connected", r.connected ? 1 : 0);
  print_value("diameter", r.diameter);
  print_value("entropy_bits", r.entropy_bits);
  print_value("max_entropy_bits", r.max_entropy_bits);
  print_value("information_index", r.information_index);
  if (g.weighted()) print_value("edge_entropy_bits", cge::ShannonEdgeEntropy<double>().compute(g));
  if (!cge_tool::standard_output_written(kProgram)) return kExitComputation;
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  CLI::App app{
      "Degree-degree association entropy H, information index I = lambda (log2|V| - H) and, for weighted\n"
      "graphs, the edge-length entropy H_W of one graph (combinatorial graph entropy, cge " CGE_VERSION_STRING
      ").\nReads an edge list (\"u v\" or \"u v w\" per line) or, with --points, a point list (\"x y "
      "[feature|semantic]\"\n"
      "per line, pixels) that is turned into a frame graph. '#' starts a comment. See docs/CLI.md.",
      kProgram};
  app.set_version_flag("--version", std::string(kProgram) + " " + CGE_VERSION_STRING);
  app.add_option("FILE", opt.file, "input file; standard input when absent or \"-\"");
  CLI::Option* points = app.add_flag("--points", opt.points, "read a point list and build the graph with GraphBuilder");
  app.add_flag("--one-based", opt.one_based, "edge list vertex ids start at 1")->excludes(points);
  app.add_option("--alpha", opt.alpha, "base of the functional alpha^E(v), > 0")->capture_default_str();
  app.add_option("--lambda", opt.lambda, "scale of the information index, > 0")->capture_default_str();
  std::string coeff = "exp", ties = "all", scaling = "raw";
  app.add_option("--coeff", coeff, "coefficients c_k: exp = rho e^(1-k), lin = rho - k + 1, const = 1")
      ->check(CLI::IsMember({"exp", "lin", "const"}))
      ->capture_default_str();
  app.add_option("--ties", ties, "how tied shortest paths count in Delta: all (multiplicity), mean, min")
      ->check(CLI::IsMember({"all", "mean", "min"}))
      ->capture_default_str();
  app.add_option("--scaling", scaling, "exponent scaling: raw (the paper) or mean (E / mean E)")
      ->check(CLI::IsMember({"raw", "mean"}))
      ->capture_default_str();
  app.add_option("--width", opt.width_px, "image width in pixels (--points)")->capture_default_str()->needs(points);
  app.add_option("--height", opt.height_px, "image height in pixels (--points)")->capture_default_str()->needs(points);
  app.add_option("--dense-threshold", opt.dense_threshold,
                 "N_th: a patch with more stable features is dense (--points)")
      ->capture_default_str()
      ->needs(points);
  app.add_option("--radius-fraction", opt.radius_fraction,
                 "base radius R as a fraction of the image diagonal (--points)")
      ->capture_default_str()
      ->needs(points);

  app.add_option("--max-vertices", opt.max_vertices,
                 "largest accepted number of vertices (max id + 1, or points); memory and time grow with it")
      ->capture_default_str();

  if (const int exit_code = cge_tool::parse_command_line(app, argc, argv, kProgram); exit_code >= 0) return exit_code;
  // The validators above admit only these names.
  opt.coeff = coeff == "lin"     ? cge::CoefficientKind::linear
              : coeff == "const" ? cge::CoefficientKind::constant
                                 : cge::CoefficientKind::exp;
  opt.ties = ties == "mean" ? cge::TieMode::mean : ties == "min" ? cge::TieMode::min : cge::TieMode::all;
  opt.scaling = scaling == "mean" ? cge::ScalingKind::normalised_mean : cge::ScalingKind::raw;

  try {
    return run(opt);
  } catch (const cge::io::ParseError& e) {
    std::fprintf(stderr, "%s: error: %s\n", kProgram, e.what());
    return kExitUsage;
  } catch (const UsageError& e) {
    std::fprintf(stderr, "%s: error: %s\n", kProgram, e.what());
    return kExitUsage;
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "%s: error: %s\n", kProgram, e.what());
    return kExitUsage;
  } catch (const std::overflow_error& e) {
    std::fprintf(stderr, "%s: error: %s\n", kProgram, e.what());
    return kExitComputation;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: error: %s\n", kProgram, e.what());
    return kExitComputation;
  }
}
