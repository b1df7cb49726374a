// Checks of cge_loop_study's output files against independent recomputation (hidden: run by
// tests/cli/run_loop_study.cmake after it ran the tool, with the folders in the environment):
//   CGE_LOOP_STUDY_OUT      the tool's --out folder (frames.csv, pairs.csv)
//   CGE_LOOP_STUDY_STDOUT   a file holding the tool's standard output
//   CGE_LOOP_STUDY_LOOPS    the dataset's loops.txt
//   CGE_LOOP_STUDY_STEP, CGE_LOOP_STUDY_MIN_GAP, CGE_LOOP_STUDY_TOLERANCE   the run's options
// The printed figures are recomputed from the CSV columns with brute-force oracles (all
// positive/negative pairs for the AUC; an explicit threshold loop for AP), the collapse flags from
// the entropy columns, the revisit labels from loops.txt and the pair set from the frame list.

#include <catch2/catch.hpp>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace {

std::vector<std::vector<std::string>> read_csv(const std::string& path, const std::string& expected_header) {
  std::ifstream in(path);
  REQUIRE(in);
  std::string line;
  REQUIRE(std::getline(in, line));
  CHECK(line == expected_header);
  std::vector<std::vector<std::string>> rows;
  while (std::getline(in, line)) {
    std::vector<std::string> fields;
    std::stringstream ss(line);
    std::string field;
    while (std::getline(ss, field, ',')) fields.push_back(field);
    rows.push_back(fields);
  }
  return rows;
}

double oracle_auc(const std::vector<std::pair<double, bool>>& scored) {
  double wins = 0, pairs = 0;
  for (const auto& p : scored) {
    if (!p.second) continue;
    for (const auto& n : scored) {
      if (n.second) continue;
      pairs += 1;
      wins += p.first > n.first ? 1.0 : (p.first == n.first ? 0.5 : 0.0);
    }
  }
  return wins / pairs;
}

double oracle_ap(const std::vector<std::pair<double, bool>>& scored) {
  std::set<double> thresholds;
  int positives = 0;
  for (const auto& s : scored) {
    thresholds.insert(s.first);
    positives += s.second;
  }
  double ap = 0, previous_recall = 0;
  for (auto t = thresholds.rbegin(); t != thresholds.rend(); ++t) {
    int tp = 0, fp = 0;
    for (const auto& s : scored) {
      if (s.first >= *t) (s.second ? tp : fp) += 1;
    }
    const double recall = static_cast<double>(tp) / positives;
    ap += (recall - previous_recall) * tp / (tp + fp);
    previous_recall = recall;
  }
  return ap;
}

}  // namespace

TEST_CASE("cge_loop_study outputs agree with recomputation (run by the CLI test)", "[.loop_study_files]") {
  const char* out = std::getenv("CGE_LOOP_STUDY_OUT");
  const char* stdout_file = std::getenv("CGE_LOOP_STUDY_STDOUT");
  const char* loops_file = std::getenv("CGE_LOOP_STUDY_LOOPS");
  const char* step_text = std::getenv("CGE_LOOP_STUDY_STEP");
  const char* gap_text = std::getenv("CGE_LOOP_STUDY_MIN_GAP");
  const char* tolerance_text = std::getenv("CGE_LOOP_STUDY_TOLERANCE");
  if (!out || !stdout_file || !loops_file || !step_text || !gap_text || !tolerance_text) {
    FAIL("run by tests/cli/run_loop_study.cmake, which sets the CGE_LOOP_STUDY_* variables");
  }
  const int step = std::stoi(step_text);
  const int min_gap = std::stoi(gap_text);
  const double tolerance = std::stod(tolerance_text);

  // loops.txt: `query_timestamp match_timestamp query_index match_index`, '#' comments.
  std::set<std::pair<int, int>> loops;
  {
    std::ifstream in(loops_file);
    REQUIRE(in);
    std::string line;
    while (std::getline(in, line)) {
      if (line.empty() || line[0] == '#') continue;
      std::stringstream ss(line);
      double tq = 0, tm = 0;
      int q = 0, m = 0;
      REQUIRE(ss >> tq >> tm >> q >> m);
      loops.emplace(q, m);
    }
  }

  const auto frames = read_csv(std::string(out) + "/frames.csv",
                               "frame,timestamp,vertices,edges,entropy_raw_bits,entropy_normalised_bits,"
                               "log2_vertices,collapsed_raw,collapsed_normalised");
  REQUIRE(frames.size() >= 2);
  std::vector<int> indices;
  int with_graph = 0, collapsed_raw = 0, collapsed_normalised = 0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const auto& r = frames[i];
    REQUIRE(r.size() == 9);
    const int frame = std::stoi(r[0]);
    CHECK(frame == static_cast<int>(i) * step);
    indices.push_back(frame);
    const int vertices = std::stoi(r[2]);
    if (vertices == 0) continue;
    ++with_graph;
    const double h_raw = std::stod(r[4]), h_norm = std::stod(r[5]), log2v = std::stod(r[6]);
    CHECK(log2v == Approx(std::log2(static_cast<double>(vertices))).margin(1e-12));
    CHECK(h_raw >= -1e-12);
    CHECK(h_raw <= log2v + 1e-9);
    CHECK(h_norm >= -1e-12);
    CHECK(h_norm <= log2v + 1e-9);
    // collapsed: |I - log2|V|| <= T with I = log2|V| - H (lambda 1), i.e. H <= T.
    CHECK(r[7] == (h_raw <= tolerance ? "1" : "0"));
    CHECK(r[8] == (h_norm <= tolerance ? "1" : "0"));
    collapsed_raw += r[7] == "1";
    collapsed_normalised += r[8] == "1";
  }

  const auto pairs = read_csv(std::string(out) + "/pairs.csv", "query,match,revisit,s_sum_raw,s_sum_normalised");
  std::set<std::pair<int, int>> expected_pairs, seen_pairs;
  for (int q : indices) {
    for (int m : indices) {
      if (q - m >= min_gap) expected_pairs.emplace(q, m);
    }
  }
  std::vector<std::pair<double, bool>> by_raw, by_normalised;
  int revisits = 0;
  for (const auto& r : pairs) {
    REQUIRE(r.size() == 5);
    const int q = std::stoi(r[0]), m = std::stoi(r[1]);
    seen_pairs.emplace(q, m);
    const bool revisit = r[2] == "1";
    CHECK((r[2] == "0" || r[2] == "1"));
    CHECK(revisit == (loops.count({q, m}) > 0));
    const double raw = std::stod(r[3]), normalised = std::stod(r[4]);
    CHECK((raw >= 0 && raw <= 1));
    CHECK((normalised >= 0 && normalised <= 1));
    by_raw.emplace_back(raw, revisit);
    by_normalised.emplace_back(normalised, revisit);
    revisits += revisit;
  }
  CHECK(seen_pairs == expected_pairs);
  CHECK(seen_pairs.size() == pairs.size());  // no pair twice
  REQUIRE(revisits > 0);
  REQUIRE(revisits < static_cast<int>(pairs.size()));

  std::map<std::string, double> printed;
  {
    std::ifstream in(stdout_file);
    REQUIRE(in);
    std::string name;
    std::string value;
    while (in >> name >> value) printed[name] = std::stod(value);
  }
  const double margin = 1e-9;  // the tool prints 12 significant digits
  CHECK(printed.at("frames") == static_cast<double>(frames.size()));
  CHECK(printed.at("pairs") == static_cast<double>(pairs.size()));
  CHECK(printed.at("revisit_pairs") == revisits);
  CHECK(printed.at("collapse_fraction_raw") == Approx(static_cast<double>(collapsed_raw) / with_graph).margin(margin));
  CHECK(printed.at("collapse_fraction_normalised") ==
        Approx(static_cast<double>(collapsed_normalised) / with_graph).margin(margin));
  CHECK(printed.at("auc_raw") == Approx(oracle_auc(by_raw)).margin(margin));
  CHECK(printed.at("auc_normalised") == Approx(oracle_auc(by_normalised)).margin(margin));
  CHECK(printed.at("average_precision_raw") == Approx(oracle_ap(by_raw)).margin(margin));
  CHECK(printed.at("average_precision_normalised") == Approx(oracle_ap(by_normalised)).margin(margin));
}
