#pragma once
// BowDatabase: an inverted index over BoW vectors. add() stores a vector and returns its entry id
// (0, 1, 2, ... in order); query() lists, for every stored entry that shares at least one word with
// the query, the number of common words and the L1 score, by visiting only the query's words'
// posting lists (cost proportional to the common words, not to the database size).
//
// Score from the common words alone: for L1-normalised vectors with non-negative weights,
// 1 - 0.5 |a - b|_1 = sum over common words of min(a_w, b_w) (cge/bow/bow_vector.hpp), so the
// database normalises what it stores and what it is asked.

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

#include "cge/bow/bow_vector.hpp"

namespace cge {
namespace bow {

struct DatabaseMatch {
  int entry = -1;        ///< id returned by add()
  int common_words = 0;  ///< words present in both vectors (>= 1)
  double score = 0;      ///< L1 score in (0, 1]
};

class BowDatabase {
 public:
  /// Stores v (normalised copy) and returns its entry id. Throws std::invalid_argument for a vector
  /// that is not sorted by word or has negative weights.
  int add(BowVector v) {
    check_bow_vector(v, "BowDatabase::add");
    l1_normalise(v);
    const int id = static_cast<int>(entries_.size());
    for (const BowEntry& e : v) postings_[e.word].push_back(Posting{id, e.weight});
    entries_.push_back(std::move(v));
    return id;
  }

  /// Every stored entry with a common word, ascending entry id.
  std::vector<DatabaseMatch> query(BowVector v) const {
    check_bow_vector(v, "BowDatabase::query");
    l1_normalise(v);
    std::vector<int> common(entries_.size(), 0);
    std::vector<double> score(entries_.size(), 0.0);
    for (const BowEntry& e : v) {
      const auto it = postings_.find(e.word);
      if (it == postings_.end()) continue;
      for (const Posting& p : it->second) {
        ++common[static_cast<std::size_t>(p.entry)];
        score[static_cast<std::size_t>(p.entry)] += std::min(p.weight, e.weight);
      }
    }
    std::vector<DatabaseMatch> out;
    for (std::size_t i = 0; i < entries_.size(); ++i) {
      if (common[i] > 0) out.push_back(DatabaseMatch{static_cast<int>(i), common[i], std::min(score[i], 1.0)});
    }
    return out;
  }

  std::size_t size() const { return entries_.size(); }
  const BowVector& entry(int id) const { return entries_.at(static_cast<std::size_t>(id)); }
  void clear() {
    entries_.clear();
    postings_.clear();
  }

 private:
  struct Posting {
    int entry;
    double weight;
  };
  std::vector<BowVector> entries_;
  // Looked up by word only, never iterated, so its order cannot leak into results.
  std::unordered_map<WordId, std::vector<Posting>> postings_;
};

}  // namespace bow
}  // namespace cge
