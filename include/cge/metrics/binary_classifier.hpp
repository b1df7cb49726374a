#pragma once
// Curves of a binary classifier from scored, labelled examples: ROC curve and its area, P-R curve
// and average precision. A higher score means "more likely positive"; an example is predicted
// positive at threshold t when score >= t.
//
// Definitions (n_pos positives, n_neg negatives, thresholds t_1 > t_2 > ... > t_m the DISTINCT
// scores; TP_k, FP_k the positives and negatives with score >= t_k):
//   ROC curve   (FPR, TPR) = (0, 0) at threshold +infinity, then (FP_k / n_neg, TP_k / n_pos) for
//               k = 1 .. m; the last point is (1, 1). Tied examples enter together (one point).
//   AUC         the Mann-Whitney statistic: the probability that a random positive scores above a
//               random negative, ties counted half:
//                 AUC = (#{(p, n): s_p > s_n} + 0.5 #{(p, n): s_p = s_n}) / (n_pos n_neg),
//               which equals the trapezoidal area under the ROC curve above.
//   P-R curve   (recall, precision) = (TP_k / n_pos, TP_k / (TP_k + FP_k)) for k = 1 .. m (no
//               point at +infinity, where precision is undefined).
//   AP          average precision, the step-wise sum over the distinct thresholds without
//               interpolation (scikit-learn's average_precision_score):
//                 AP = sum_{k=1..m} (R_k - R_{k-1}) P_k,  R_0 = 0,
//               i.e. each threshold's precision weighted by the recall it adds; a block of tied
//               scores counts once, with the precision of the whole block.
// Errors: std::invalid_argument for an empty input, a NaN score (naming its index), or a class
// missing where the quantity is undefined: the ROC curve and AUC need both classes; the P-R curve
// and AP need at least one positive (without negatives every precision is 1, AP = 1).
// Infinite scores are ordinary (extreme) scores. Cost O(n log n); the result does not depend on
// the order of the input.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace cge {
namespace metrics {

/// One example: the classifier's score and the truth.
struct LabelledScore {
  double score = 0;
  bool positive = false;
};

struct RocPoint {
  double threshold = 0;            ///< predicted positive when score >= threshold (+inf: none)
  std::size_t true_positives = 0;  ///< positives with score >= threshold
  std::size_t false_positives = 0;
  double false_positive_rate = 0;  ///< false_positives / n_neg
  double true_positive_rate = 0;   ///< true_positives / n_pos
};

struct PrPoint {
  double threshold = 0;
  std::size_t true_positives = 0;
  std::size_t false_positives = 0;
  double recall = 0;     ///< true_positives / n_pos
  double precision = 0;  ///< true_positives / (true_positives + false_positives)
};

namespace detail {

/// Per distinct score, descending: the cumulative (TP, FP) counts at that threshold.
struct ThresholdCounts {
  double threshold;
  std::size_t tp;
  std::size_t fp;
};

struct ClassCounts {
  std::size_t positives = 0;
  std::size_t negatives = 0;
};

inline ClassCounts check_examples(const std::vector<LabelledScore>& examples, const char* who) {
  if (examples.empty()) throw std::invalid_argument(std::string(who) + ": no examples");
  ClassCounts c;
  for (std::size_t i = 0; i < examples.size(); ++i) {
    if (std::isnan(examples[i].score)) {
      throw std::invalid_argument(std::string(who) + ": the score of example " + std::to_string(i) + " is NaN");
    }
    (examples[i].positive ? c.positives : c.negatives) += 1;
  }
  return c;
}

inline std::vector<ThresholdCounts> threshold_counts(std::vector<LabelledScore> examples) {
  std::sort(examples.begin(), examples.end(),
            [](const LabelledScore& a, const LabelledScore& b) { return a.score > b.score; });
  std::vector<ThresholdCounts> out;
  std::size_t tp = 0, fp = 0;
  for (std::size_t i = 0; i < examples.size(); ++i) {
    (examples[i].positive ? tp : fp) += 1;
    const bool last_of_block = i + 1 == examples.size() || examples[i + 1].score != examples[i].score;
    if (last_of_block) out.push_back({examples[i].score, tp, fp});
  }
  return out;
}

}  // namespace detail

/// The ROC curve: (0, 0) at +infinity, then one point per distinct score, descending thresholds.
inline std::vector<RocPoint> roc_curve(const std::vector<LabelledScore>& examples) {
  const detail::ClassCounts c = detail::check_examples(examples, "roc_curve");
  if (c.positives == 0 || c.negatives == 0) {
    throw std::invalid_argument("roc_curve: the ROC curve needs both positive and negative examples (got " +
                                std::to_string(c.positives) + " positive, " + std::to_string(c.negatives) +
                                " negative)");
  }
  std::vector<RocPoint> curve;
  RocPoint start;
  start.threshold = std::numeric_limits<double>::infinity();
  curve.push_back(start);
  for (const detail::ThresholdCounts& t : detail::threshold_counts(examples)) {
    RocPoint p;
    p.threshold = t.threshold;
    p.true_positives = t.tp;
    p.false_positives = t.fp;
    p.true_positive_rate = static_cast<double>(t.tp) / static_cast<double>(c.positives);
    p.false_positive_rate = static_cast<double>(t.fp) / static_cast<double>(c.negatives);
    curve.push_back(p);
  }
  return curve;
}

/// Area under the ROC curve (the Mann-Whitney statistic, ties counted half), in [0, 1].
inline double roc_auc(const std::vector<LabelledScore>& examples) {
  const std::vector<RocPoint> curve = roc_curve(examples);
  // Trapezoids in counts (exact integers up to 2^53), divided once at the end: a block of tied
  // scores adding dp positives and dn negatives contributes dn (tp_before + dp / 2) pairs.
  double pairs = 0;
  for (std::size_t k = 1; k < curve.size(); ++k) {
    const double dn = static_cast<double>(curve[k].false_positives - curve[k - 1].false_positives);
    const double tp_sum = static_cast<double>(curve[k].true_positives + curve[k - 1].true_positives);
    pairs += dn * tp_sum / 2;
  }
  const RocPoint& last = curve.back();
  return pairs / (static_cast<double>(last.true_positives) * static_cast<double>(last.false_positives));
}

/// The P-R curve: one point per distinct score, descending thresholds (recall non-decreasing).
inline std::vector<PrPoint> pr_curve(const std::vector<LabelledScore>& examples) {
  const detail::ClassCounts c = detail::check_examples(examples, "pr_curve");
  if (c.positives == 0) throw std::invalid_argument("pr_curve: recall is undefined without positive examples");
  std::vector<PrPoint> curve;
  for (const detail::ThresholdCounts& t : detail::threshold_counts(examples)) {
    PrPoint p;
    p.threshold = t.threshold;
    p.true_positives = t.tp;
    p.false_positives = t.fp;
    p.recall = static_cast<double>(t.tp) / static_cast<double>(c.positives);
    p.precision = static_cast<double>(t.tp) / static_cast<double>(t.tp + t.fp);
    curve.push_back(p);
  }
  return curve;
}

/// Average precision: sum over the distinct thresholds of (R_k - R_{k-1}) P_k, R_0 = 0; in (0, 1].
inline double average_precision(const std::vector<LabelledScore>& examples) {
  double ap = 0;
  double previous_recall = 0;
  for (const PrPoint& p : pr_curve(examples)) {
    ap += (p.recall - previous_recall) * p.precision;
    previous_recall = p.recall;
  }
  return ap;
}

}  // namespace metrics
}  // namespace cge
