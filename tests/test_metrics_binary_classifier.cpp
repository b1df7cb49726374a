// ROC / P-R curves, AUC and average precision: hand-worked small cases, and random inputs with
// many ties against brute-force oracles (all positive/negative pairs for the AUC; an explicit loop
// over the thresholds, counting every example again, for the curves and AP).

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <random>
#include <set>
#include <stdexcept>
#include <vector>

#include "cge/metrics/binary_classifier.hpp"

using cge::metrics::LabelledScore;

namespace {

std::vector<LabelledScore> examples(const std::vector<double>& scores, const std::vector<int>& labels) {
  std::vector<LabelledScore> out;
  for (std::size_t i = 0; i < scores.size(); ++i) out.push_back({scores[i], labels[i] != 0});
  return out;
}

double brute_auc(const std::vector<LabelledScore>& ex) {
  double wins = 0, pairs = 0;
  for (const LabelledScore& p : ex) {
    if (!p.positive) continue;
    for (const LabelledScore& n : ex) {
      if (n.positive) continue;
      pairs += 1;
      if (p.score > n.score) wins += 1;
      if (p.score == n.score) wins += 0.5;
    }
  }
  return wins / pairs;
}

struct BruteCounts {
  double threshold;
  int tp, fp;
};

/// For every distinct score, descending, count the examples at or above it from scratch.
std::vector<BruteCounts> brute_thresholds(const std::vector<LabelledScore>& ex) {
  std::set<double> distinct;
  for (const LabelledScore& e : ex) distinct.insert(e.score);
  std::vector<BruteCounts> out;
  for (auto it = distinct.rbegin(); it != distinct.rend(); ++it) {
    BruteCounts c{*it, 0, 0};
    for (const LabelledScore& e : ex) {
      if (e.score >= *it) (e.positive ? c.tp : c.fp) += 1;
    }
    out.push_back(c);
  }
  return out;
}

double brute_ap(const std::vector<LabelledScore>& ex) {
  int positives = 0;
  for (const LabelledScore& e : ex) positives += e.positive;
  double ap = 0, previous_recall = 0;
  for (const BruteCounts& c : brute_thresholds(ex)) {
    const double recall = static_cast<double>(c.tp) / positives;
    ap += (recall - previous_recall) * c.tp / (c.tp + c.fp);
    previous_recall = recall;
  }
  return ap;
}

}  // namespace

TEST_CASE("binary classifier: hand-worked case without ties", "[metrics][roc]") {
  // Scores 0.9+ 0.8- 0.7+ 0.6- : positive/negative pairs (0.9,0.8) (0.9,0.6) (0.7,0.6) won, (0.7,0.8)
  // lost: AUC 3/4. P-R: at 0.9 (R 1/2, P 1), 0.8 (1/2, 1/2), 0.7 (1, 2/3), 0.6 (1, 1/2);
  // AP = 1/2 * 1 + 0 + 1/2 * 2/3 = 5/6.
  const auto ex = examples({0.8, 0.9, 0.6, 0.7}, {0, 1, 0, 1});
  CHECK(cge::metrics::roc_auc(ex) == Approx(0.75).margin(1e-15));
  CHECK(cge::metrics::average_precision(ex) == Approx(5.0 / 6.0).margin(1e-15));
  const auto roc = cge::metrics::roc_curve(ex);
  REQUIRE(roc.size() == 5);
  CHECK(std::isinf(roc[0].threshold));
  CHECK(roc[0].true_positive_rate == 0);
  CHECK(roc[0].false_positive_rate == 0);
  CHECK(roc[1].threshold == 0.9);
  CHECK(roc[1].true_positive_rate == 0.5);
  CHECK(roc[2].false_positive_rate == 0.5);
  CHECK(roc[4].true_positive_rate == 1);
  CHECK(roc[4].false_positive_rate == 1);
  const auto pr = cge::metrics::pr_curve(ex);
  REQUIRE(pr.size() == 4);
  CHECK(pr[1].recall == 0.5);
  CHECK(pr[1].precision == 0.5);
  CHECK(pr[2].precision == Approx(2.0 / 3.0));
}

TEST_CASE("binary classifier: hand-worked case with ties", "[metrics][roc]") {
  // Scores: 1+ 1- 0.5+ 0.5+ 0.5- 0-. Pairs (3 x 3 = 9): positive 1 vs negatives (1 tie, 0.5 win,
  // 0 win) = 2.5; each positive 0.5 vs (1 lose, 0.5 tie, 0 win) = 1.5 twice: AUC = 5.5 / 9.
  // P-R blocks: t = 1: TP 1 FP 1 (R 1/3, P 1/2); t = 0.5: TP 3 FP 2 (R 1, P 3/5); t = 0: (1, 1/2).
  // AP = 1/3 * 1/2 + 2/3 * 3/5 = 1/6 + 2/5 = 17/30.
  const auto ex = examples({1, 1, 0.5, 0.5, 0.5, 0}, {1, 0, 1, 1, 0, 0});
  CHECK(cge::metrics::roc_auc(ex) == Approx(5.5 / 9).margin(1e-15));
  CHECK(cge::metrics::average_precision(ex) == Approx(17.0 / 30.0).margin(1e-15));
  CHECK(cge::metrics::roc_curve(ex).size() == 4);  // +inf and three distinct scores

  // All scores equal: the classifier cannot rank, AUC 1/2, AP = the positive fraction.
  const auto flat = examples({2, 2, 2, 2}, {1, 0, 0, 0});
  CHECK(cge::metrics::roc_auc(flat) == 0.5);
  CHECK(cge::metrics::average_precision(flat) == 0.25);
  // Perfectly separated, and perfectly inverted.
  CHECK(cge::metrics::roc_auc(examples({3, 2, 1}, {1, 1, 0})) == 1);
  CHECK(cge::metrics::roc_auc(examples({3, 2, 1}, {0, 1, 1})) == 0);
  CHECK(cge::metrics::average_precision(examples({3, 2, 1}, {1, 1, 0})) == 1);
  // Infinite scores are ordinary extreme scores.
  const double inf = std::numeric_limits<double>::infinity();
  CHECK(cge::metrics::roc_auc(examples({inf, -inf, 0}, {1, 0, 0})) == 1);
}

TEST_CASE("binary classifier: errors", "[metrics][roc]") {
  using cge::metrics::average_precision;
  using cge::metrics::roc_auc;
  CHECK_THROWS_AS(roc_auc({}), std::invalid_argument);
  CHECK_THROWS_AS(average_precision({}), std::invalid_argument);
  CHECK_THROWS_WITH(roc_auc(examples({1, 2}, {1, 1})), Catch::Contains("both positive and negative"));
  CHECK_THROWS_WITH(roc_auc(examples({1, 2}, {0, 0})), Catch::Contains("both positive and negative"));
  CHECK_THROWS_WITH(average_precision(examples({1, 2}, {0, 0})), Catch::Contains("without positive"));
  CHECK(average_precision(examples({1, 2}, {1, 1})) == 1);  // no negatives: every precision is 1
  CHECK_THROWS_WITH(roc_auc(examples({1, std::nan(""), 0}, {1, 0, 0})), Catch::Contains("example 1 is NaN"));
  CHECK_THROWS_WITH(cge::metrics::pr_curve(examples({std::nan("")}, {1})), Catch::Contains("NaN"));
}

TEST_CASE("binary classifier: random inputs with ties against brute force", "[metrics][roc]") {
  std::mt19937_64 rng(20261122);
  for (int trial = 0; trial < 300; ++trial) {
    const int n = 2 + static_cast<int>(rng() % 60);
    const int levels = 1 + static_cast<int>(rng() % 8);  // few distinct scores: many ties
    std::vector<LabelledScore> ex;
    for (int i = 0; i < n; ++i) {
      ex.push_back({static_cast<double>(rng() % static_cast<unsigned>(levels)) / 4.0, (rng() % 3) == 0});
    }
    ex[0].positive = true;  // both classes present
    ex[1].positive = false;
    INFO("trial " << trial << ", " << n << " examples");
    CHECK(cge::metrics::roc_auc(ex) == Approx(brute_auc(ex)).margin(1e-12));
    CHECK(cge::metrics::average_precision(ex) == Approx(brute_ap(ex)).margin(1e-12));

    const std::vector<BruteCounts> oracle = brute_thresholds(ex);
    const auto roc = cge::metrics::roc_curve(ex);
    const auto pr = cge::metrics::pr_curve(ex);
    REQUIRE(roc.size() == oracle.size() + 1);
    REQUIRE(pr.size() == oracle.size());
    for (std::size_t k = 0; k < oracle.size(); ++k) {
      CHECK(pr[k].threshold == oracle[k].threshold);
      CHECK(pr[k].true_positives == static_cast<std::size_t>(oracle[k].tp));
      CHECK(pr[k].false_positives == static_cast<std::size_t>(oracle[k].fp));
      CHECK(roc[k + 1].true_positives == static_cast<std::size_t>(oracle[k].tp));
      CHECK(roc[k + 1].false_positives == static_cast<std::size_t>(oracle[k].fp));
    }
    // Input order does not matter.
    std::vector<LabelledScore> shuffled = ex;
    std::shuffle(shuffled.begin(), shuffled.end(), rng);
    CHECK(cge::metrics::roc_auc(shuffled) == cge::metrics::roc_auc(ex));
    CHECK(cge::metrics::average_precision(shuffled) == cge::metrics::average_precision(ex));
  }
}
