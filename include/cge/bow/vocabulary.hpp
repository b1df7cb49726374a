#pragma once
// Vocabulary: a hierarchical bag-of-words vocabulary for 256-bit binary descriptors (ORB), our own
// implementation of the scheme of Nister and Stewenius (vocabulary tree) as DBoW2 uses it for ORB:
// k-medians clustering with majority-bit centres, k-means++ seeding, TF-IDF weights, L1 score.
//
// Tree: the root (node 0, no centre) has up to `branching` (k) children; every node is split again
// until `depth` (L) levels below the root, or until its cluster holds no more than k distinct
// descriptors (then each distinct descriptor becomes a child leaf), or all its descriptors are
// equal. Leaves are the words, numbered 0, 1, ... in node order. Nodes are numbered breadth-first,
// so the children of a node are consecutive.
// Descent: from the root, move to the child whose centre is nearest in Hamming distance (the first
// such child on ties) until a leaf: that leaf is the descriptor's word.
// Weights: idf(w) = ln(N / n_w) with N training images and n_w of them containing w (after
// descent). A BoW vector holds tf-idf: count(w in image) * idf(w), then L1-normalised; words with
// weight 0 (present in every training image) are left out.
//
// Determinism: training draws random numbers only from the caller's engine (through
// cge::uniform_unit_double, so the same seed gives the same tree on every platform); ties are broken
// by index. Same descriptors, settings and engine state: the same vocabulary, bit for bit.
//
// File format (text, version 1; docs/LOOP_CLOSING.md):
//   line 1: "CGE_VOCABULARY 1"
//   line 2: "branching <k> depth <L> training_images <N> nodes <n>"
//   then n - 1 lines, nodes 1 .. n - 1 in id order: "<parent id> <weight> <64 hex digits>"
//   (parent ids non-decreasing, parent < id; weight = idf for a leaf, 0 for an inner node, written
//   with 17 significant digits so it reads back exactly; hex = the 32 descriptor bytes in order).
// Lines starting with '#' after line 2 are comments. Errors name the source and line.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <istream>
#include <limits>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "cge/bow/binary_descriptor.hpp"
#include "cge/bow/bow_vector.hpp"
#include "cge/core/bits.hpp"
#include "cge/core/uniform_double.hpp"

namespace cge {
namespace bow {

struct VocabularySettings {
  /// k: children per node, >= 2. DBoW2's ORB vocabulary uses 10.
  int branching = 10;
  /// L: levels below the root, >= 1; at most k^L words. ORB-SLAM2's vocabulary uses 6 (10^6
  /// words, trained on a large corpus); 4 (10^4 words) suits vocabularies trained from a few dozen
  /// frames in seconds.
  int depth = 4;
  /// Largest number of assign/update rounds of k-medians at one node (it stops earlier when no
  /// assignment changes), >= 1.
  int max_iterations = 10;

  void validate() const {
    if (branching < 2) throw std::invalid_argument("VocabularySettings: branching (k) must be at least 2");
    if (depth < 1) throw std::invalid_argument("VocabularySettings: depth (L) must be at least 1");
    if (max_iterations < 1) throw std::invalid_argument("VocabularySettings: max_iterations must be at least 1");
    double words = 1;
    for (int i = 0; i < depth; ++i) words *= branching;
    if (words > 1e9) throw std::invalid_argument("VocabularySettings: branching^depth exceeds 1e9 words");
  }
};

class Vocabulary {
 public:
  struct Node {
    BinaryDescriptor centre{0, 0, 0, 0};  ///< cluster centre (unused for the root)
    NodeId parent = 0;                    ///< the root is its own parent
    NodeId first_child = 0;               ///< children are first_child .. first_child + child_count - 1
    std::uint32_t child_count = 0;        ///< 0 for a leaf (a word)
    int level = 0;                        ///< 0 for the root
    double weight = 0;                    ///< idf for a word, 0 for an inner node
    std::int64_t word = -1;               ///< word id of a leaf, -1 for an inner node
  };

  /// An empty vocabulary (no words); transform() of anything gives an empty vector.
  Vocabulary() { nodes_.push_back(Node{}); }

  /// Trains from descriptors grouped by training image (one inner vector per image; at least one
  /// descriptor overall). Engine: a uniform random bit generator as cge/core/uniform_double.hpp
  /// requires (e.g. std::mt19937_64 seeded by the caller).
  template <typename Engine>
  static Vocabulary train(const std::vector<std::vector<BinaryDescriptor>>& images, const VocabularySettings& settings,
                          Engine& engine);

  int branching() const { return branching_; }
  int depth() const { return depth_; }
  int training_images() const { return training_images_; }
  std::size_t word_count() const { return word_nodes_.size(); }
  std::size_t node_count() const { return nodes_.size(); }
  bool empty() const { return word_nodes_.empty(); }
  const std::vector<Node>& nodes() const { return nodes_; }
  NodeId word_node(WordId w) const { return word_nodes_.at(w); }
  double word_weight(WordId w) const { return nodes_[word_node(w)].weight; }

  /// The word of one descriptor (descent from the root). Requires a non-empty vocabulary.
  WordId word_of(const BinaryDescriptor& d) const { return static_cast<WordId>(nodes_[descend(d, depth_)].word); }

  /// The node reached after descending at most `level` levels (the word when the leaf is shallower).
  NodeId descend(const BinaryDescriptor& d, int level) const {
    if (empty()) throw std::logic_error("Vocabulary: descent in an empty vocabulary");
    NodeId n = 0;
    while (nodes_[n].child_count > 0 && nodes_[n].level < level) {
      const Node& node = nodes_[n];
      NodeId best = node.first_child;
      int best_d = std::numeric_limits<int>::max();
      for (NodeId c = node.first_child; c < node.first_child + node.child_count; ++c) {
        const int dist = hamming_distance(d, nodes_[c].centre);
        if (dist < best_d) {
          best_d = dist;
          best = c;
        }
      }
      n = best;
    }
    return n;
  }

  /// The L1-normalised tf-idf vector of one image's descriptors. When `direct` is given it receives
  /// the direct index: feature i is listed under its ancestor at `direct_index_level` (levels
  /// below the root; its word when that is shallower).
  BowVector transform(const std::vector<BinaryDescriptor>& features, FeatureVector* direct = nullptr,
                      int direct_index_level = 2) const {
    if (direct != nullptr) direct->clear();
    if (empty()) return {};
    std::vector<std::pair<WordId, int>> hits;  // (word, feature)
    hits.reserve(features.size());
    for (std::size_t i = 0; i < features.size(); ++i) {
      const NodeId leaf = descend(features[i], depth_);
      hits.emplace_back(static_cast<WordId>(nodes_[leaf].word), static_cast<int>(i));
      if (direct != nullptr) {
        NodeId a = leaf;
        while (nodes_[a].level > direct_index_level) a = nodes_[a].parent;
        (*direct)[a].push_back(static_cast<int>(i));
      }
    }
    std::sort(hits.begin(), hits.end());
    BowVector v;
    for (std::size_t i = 0; i < hits.size();) {
      std::size_t j = i;
      while (j < hits.size() && hits[j].first == hits[i].first) ++j;
      const double w = static_cast<double>(j - i) * word_weight(hits[i].first);
      if (w > 0) v.push_back(BowEntry{hits[i].first, w});
      i = j;
    }
    l1_normalise(v);
    return v;
  }

  // ---- persistence -------------------------------------------------------------------------------
  void save(std::ostream& out) const {
    out << "CGE_VOCABULARY 1\n";
    out << "branching " << branching_ << " depth " << depth_ << " training_images " << training_images_ << " nodes "
        << nodes_.size() << "\n";
    char weight[64];
    for (std::size_t i = 1; i < nodes_.size(); ++i) {
      const Node& n = nodes_[i];
      std::snprintf(weight, sizeof weight, "%.17g", n.weight);
      out << n.parent << ' ' << weight << ' ';
      static const char* hex = "0123456789abcdef";
      for (int b = 0; b < 32; ++b) {
        const std::uint8_t byte = descriptor_byte(n.centre, b);
        out << hex[byte >> 4] << hex[byte & 15];
      }
      out << '\n';
    }
    if (!out) throw std::runtime_error("Vocabulary::save: writing failed");
  }

  /// Writes `path`; refuses (std::invalid_argument) when the file exists and overwrite is false.
  void save_file(const std::string& path, bool overwrite = false) const {
    if (!overwrite) {
      std::ifstream probe(path);
      if (probe.good()) {
        throw std::invalid_argument("Vocabulary::save_file: " + path + " exists (not overwritten)");
      }
    }
    std::ofstream out(path, std::ios::trunc);
    if (!out) throw std::invalid_argument("Vocabulary::save_file: cannot open " + path + " for writing");
    save(out);
    out.close();
    if (!out) throw std::runtime_error("Vocabulary::save_file: writing " + path + " failed");
  }

  /// Reads the text format above; `source` names the input in error messages ("file:line: ...").
  static Vocabulary load(std::istream& in, const std::string& source = "vocabulary");

  static Vocabulary load_file(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw std::invalid_argument("Vocabulary::load_file: cannot open " + path);
    return load(in, path);
  }

  bool operator==(const Vocabulary& o) const {
    if (branching_ != o.branching_ || depth_ != o.depth_ || training_images_ != o.training_images_ ||
        nodes_.size() != o.nodes_.size()) {
      return false;
    }
    for (std::size_t i = 0; i < nodes_.size(); ++i) {
      const Node& a = nodes_[i];
      const Node& b = o.nodes_[i];
      if (a.centre != b.centre || a.parent != b.parent || a.first_child != b.first_child ||
          a.child_count != b.child_count || a.level != b.level || a.weight != b.weight || a.word != b.word) {
        return false;
      }
    }
    return true;
  }
  bool operator!=(const Vocabulary& o) const { return !(*this == o); }

 private:
  int branching_ = 10;
  int depth_ = 4;
  int training_images_ = 0;
  std::vector<Node> nodes_;
  std::vector<NodeId> word_nodes_;

  /// Numbers the leaves and links children after nodes_ (parents, levels) are complete.
  void index_words() {
    word_nodes_.clear();
    for (std::size_t i = 0; i < nodes_.size(); ++i) {
      nodes_[i].word = -1;
      if (nodes_[i].child_count == 0 && i > 0) {
        nodes_[i].word = static_cast<std::int64_t>(word_nodes_.size());
        word_nodes_.push_back(static_cast<NodeId>(i));
      }
    }
  }

  template <typename Engine>
  static std::size_t uniform_index(Engine& engine, std::size_t n) {
    const std::size_t i = static_cast<std::size_t>(uniform_unit_double(engine) * static_cast<double>(n));
    return i < n ? i : n - 1;
  }

  /// k-medians++ of the descriptors pool[idx]: returns one cluster (indices into pool) per centre
  /// that ended non-empty, in centre order.
  template <typename Engine>
  static std::vector<std::vector<std::uint32_t>> k_medians(const std::vector<BinaryDescriptor>& pool,
                                                           const std::vector<std::uint32_t>& idx, int k,
                                                           int max_iterations, Engine& engine,
                                                           std::vector<BinaryDescriptor>& centres);
};

// ---- implementation ---------------------------------------------------------------------------------

template <typename Engine>
std::vector<std::vector<std::uint32_t>> Vocabulary::k_medians(const std::vector<BinaryDescriptor>& pool,
                                                              const std::vector<std::uint32_t>& idx, int k,
                                                              int max_iterations, Engine& engine,
                                                              std::vector<BinaryDescriptor>& centres) {
  const std::size_t n = idx.size();
  // k-means++ seeding: the first centre uniformly, each next one with probability proportional to
  // the squared distance to the nearest centre chosen so far.
  centres.clear();
  centres.push_back(pool[idx[uniform_index(engine, n)]]);
  std::vector<double> nearest_sq(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double d = hamming_distance(pool[idx[i]], centres[0]);
    nearest_sq[i] = d * d;
  }
  while (static_cast<int>(centres.size()) < k) {
    double total = 0;
    for (double v : nearest_sq) total += v;
    if (!(total > 0)) break;  // every descriptor equals a centre already
    const double target = uniform_unit_double(engine) * total;
    double acc = 0;
    std::size_t pick = n;
    for (std::size_t i = 0; i < n; ++i) {
      if (nearest_sq[i] <= 0) continue;
      acc += nearest_sq[i];
      pick = i;  // the last positive one, should rounding leave target >= acc
      if (acc > target) break;
    }
    centres.push_back(pool[idx[pick]]);
    for (std::size_t i = 0; i < n; ++i) {
      const double d = hamming_distance(pool[idx[i]], centres.back());
      nearest_sq[i] = std::min(nearest_sq[i], d * d);
    }
  }
  // k-medians: assign to the nearest centre (first on ties), centre = majority bit of its members
  // (a bit is 1 when more than half the members have it).
  const std::size_t kc = centres.size();
  std::vector<std::uint32_t> assignment(n, std::numeric_limits<std::uint32_t>::max());
  std::vector<int> ones(static_cast<std::size_t>(kc) * descriptor_bits);
  std::vector<int> members(kc);
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    bool changed = false;
    for (std::size_t i = 0; i < n; ++i) {
      std::uint32_t best = 0;
      int best_d = std::numeric_limits<int>::max();
      for (std::size_t c = 0; c < kc; ++c) {
        const int d = hamming_distance(pool[idx[i]], centres[c]);
        if (d < best_d) {
          best_d = d;
          best = static_cast<std::uint32_t>(c);
        }
      }
      if (assignment[i] != best) {
        assignment[i] = best;
        changed = true;
      }
    }
    if (!changed) break;
    std::fill(ones.begin(), ones.end(), 0);
    std::fill(members.begin(), members.end(), 0);
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t c = assignment[i];
      ++members[c];
      int* row = &ones[c * descriptor_bits];
      const BinaryDescriptor& d = pool[idx[i]];
      for (int w = 0; w < 4; ++w) {
        std::uint64_t bits = d[static_cast<std::size_t>(w)];
        while (bits != 0) {
          const int b = cge::detail::lowest_bit(bits);
          ++row[64 * w + b];
          bits &= bits - 1;
        }
      }
    }
    for (std::size_t c = 0; c < kc; ++c) {
      if (members[c] == 0) continue;  // keep the old centre; the cluster is dropped if it stays empty
      BinaryDescriptor m{0, 0, 0, 0};
      const int* row = &ones[c * descriptor_bits];
      for (int b = 0; b < descriptor_bits; ++b) {
        if (2 * row[b] > members[c]) m[static_cast<std::size_t>(b / 64)] |= std::uint64_t{1} << (b % 64);
      }
      centres[c] = m;
    }
  }
  // Final assignment to the final centres, so each member's cluster is the one descent would pick.
  std::vector<std::vector<std::uint32_t>> clusters(kc);
  for (std::size_t i = 0; i < n; ++i) {
    std::size_t best = 0;
    int best_d = std::numeric_limits<int>::max();
    for (std::size_t c = 0; c < kc; ++c) {
      const int d = hamming_distance(pool[idx[i]], centres[c]);
      if (d < best_d) {
        best_d = d;
        best = c;
      }
    }
    clusters[best].push_back(idx[i]);
  }
  std::vector<std::vector<std::uint32_t>> kept;
  std::vector<BinaryDescriptor> kept_centres;
  for (std::size_t c = 0; c < kc; ++c) {
    if (clusters[c].empty()) continue;
    kept.push_back(std::move(clusters[c]));
    kept_centres.push_back(centres[c]);
  }
  centres.swap(kept_centres);
  return kept;
}

template <typename Engine>
Vocabulary Vocabulary::train(const std::vector<std::vector<BinaryDescriptor>>& images,
                             const VocabularySettings& settings, Engine& engine) {
  settings.validate();
  std::vector<BinaryDescriptor> pool;
  for (const auto& img : images) pool.insert(pool.end(), img.begin(), img.end());
  if (pool.empty()) throw std::invalid_argument("Vocabulary::train: no descriptors to train from");
  if (pool.size() >= std::numeric_limits<std::uint32_t>::max()) {
    throw std::invalid_argument("Vocabulary::train: too many descriptors (2^32 or more)");
  }
  Vocabulary v;
  v.branching_ = settings.branching;
  v.depth_ = settings.depth;
  v.training_images_ = static_cast<int>(images.size());
  v.nodes_.assign(1, Node{});

  // Breadth-first: each queued node carries its members; its children are appended together.
  std::vector<std::vector<std::uint32_t>> members(1);
  members[0].resize(pool.size());
  for (std::size_t i = 0; i < pool.size(); ++i) members[0][i] = static_cast<std::uint32_t>(i);
  std::vector<BinaryDescriptor> centres;
  for (std::size_t node = 0; node < v.nodes_.size(); ++node) {
    std::vector<std::uint32_t> mine;
    mine.swap(members[node]);
    if (v.nodes_[node].level >= settings.depth || mine.empty()) continue;
    // Distinct descriptors, in order of first appearance.
    std::vector<std::uint32_t> distinct;
    {
      std::vector<std::uint32_t> sorted = mine;
      std::sort(sorted.begin(), sorted.end(),
                [&](std::uint32_t a, std::uint32_t b) { return pool[a] != pool[b] ? pool[a] < pool[b] : a < b; });
      std::vector<std::uint32_t> firsts;
      for (std::size_t i = 0; i < sorted.size(); ++i) {
        if (i == 0 || pool[sorted[i]] != pool[sorted[i - 1]]) firsts.push_back(sorted[i]);
        if (firsts.size() > static_cast<std::size_t>(settings.branching)) break;
      }
      distinct = firsts;
      std::sort(distinct.begin(), distinct.end());
    }
    if (distinct.size() <= 1 && node != 0) continue;  // all equal: a leaf
    std::vector<std::vector<std::uint32_t>> clusters;
    if (distinct.size() <= static_cast<std::size_t>(settings.branching)) {
      // Few distinct descriptors: one child leaf each, holding its copies.
      centres.clear();
      for (std::uint32_t d : distinct) centres.push_back(pool[d]);
      clusters.assign(centres.size(), {});
      for (std::uint32_t i : mine) {
        for (std::size_t c = 0; c < centres.size(); ++c) {
          if (pool[i] == centres[c]) {
            clusters[c].push_back(i);
            break;
          }
        }
      }
    } else {
      clusters = k_medians(pool, mine, settings.branching, settings.max_iterations, engine, centres);
    }
    const bool leaves = distinct.size() <= static_cast<std::size_t>(settings.branching);
    v.nodes_[node].first_child = static_cast<NodeId>(v.nodes_.size());
    v.nodes_[node].child_count = static_cast<std::uint32_t>(clusters.size());
    const int child_level = v.nodes_[node].level + 1;
    for (std::size_t c = 0; c < clusters.size(); ++c) {
      Node child;
      child.centre = centres[c];
      child.parent = static_cast<NodeId>(node);
      child.level = child_level;
      v.nodes_.push_back(child);
      members.push_back(leaves ? std::vector<std::uint32_t>{} : std::move(clusters[c]));
    }
  }
  v.index_words();

  // idf from the training images, by descent (what transform() will do).
  std::vector<int> images_with(v.word_count(), 0);
  std::vector<int> last_image(v.word_count(), -1);
  for (std::size_t im = 0; im < images.size(); ++im) {
    for (const BinaryDescriptor& d : images[im]) {
      const WordId w = v.word_of(d);
      if (last_image[w] != static_cast<int>(im)) {
        last_image[w] = static_cast<int>(im);
        ++images_with[w];
      }
    }
  }
  const double n_images = static_cast<double>(images.size());
  for (std::size_t w = 0; w < v.word_count(); ++w) {
    // A word no training descriptor descends to (possible when centres moved) gets the largest idf.
    const double n_w = images_with[w] > 0 ? images_with[w] : 1;
    v.nodes_[v.word_nodes_[w]].weight = std::log(n_images / n_w);
  }
  return v;
}

inline Vocabulary Vocabulary::load(std::istream& in, const std::string& source) {
  int line_no = 0;
  std::string line;
  auto fail = [&](const std::string& what) -> void {
    throw std::invalid_argument(source + ":" + std::to_string(line_no) + ": " + what);
  };
  auto next_line = [&]() -> bool {
    while (std::getline(in, line)) {
      ++line_no;
      if (!line.empty() && line.back() == '\r') line.pop_back();
      if (line_no > 2 && (line.empty() || line[0] == '#')) continue;
      return true;
    }
    return false;
  };
  if (!next_line()) {
    line_no = 1;
    fail("empty input, expected the header \"CGE_VOCABULARY 1\"");
  }
  {
    std::istringstream h(line);
    std::string magic;
    int version = 0;
    if (!(h >> magic) || magic != "CGE_VOCABULARY") fail("not a cge vocabulary (expected \"CGE_VOCABULARY 1\")");
    if (!(h >> version)) fail("missing format version after CGE_VOCABULARY");
    if (version != 1)
      fail("unsupported vocabulary format version " + std::to_string(version) + " (this build reads 1)");
  }
  Vocabulary v;
  long long node_count = 0;
  {
    if (!next_line()) fail("missing the line \"branching <k> depth <L> training_images <N> nodes <n>\"");
    std::istringstream h(line);
    std::string k1, k2, k3, k4, rest;
    if (!(h >> k1 >> v.branching_ >> k2 >> v.depth_ >> k3 >> v.training_images_ >> k4 >> node_count) ||
        k1 != "branching" || k2 != "depth" || k3 != "training_images" || k4 != "nodes" || (h >> rest)) {
      fail("expected \"branching <k> depth <L> training_images <N> nodes <n>\"");
    }
    VocabularySettings s;
    s.branching = v.branching_;
    s.depth = v.depth_;
    try {
      s.validate();
    } catch (const std::invalid_argument& e) {
      fail(e.what());
    }
    if (v.training_images_ < 0) fail("training_images must not be negative");
    if (node_count < 1 || node_count > 2000000000LL) fail("nodes must be in 1 .. 2e9");
    // A tree of branching k and depth L has at most 1 + k + ... + k^L nodes (at most 2e9, as
    // validate() bounds k^L by 1e9): a larger count is a damaged header, refused before anything
    // is allocated for it.
    long long most = 1, level = 1;
    for (int d = 0; d < v.depth_; ++d) {
      level *= v.branching_;
      most += level;
    }
    if (node_count > most) {
      fail("nodes " + std::to_string(node_count) + " exceeds the " + std::to_string(most) +
           " nodes a tree of branching " + std::to_string(v.branching_) + " and depth " + std::to_string(v.depth_) +
           " can have");
    }
  }
  v.nodes_.assign(1, Node{});
  // Reserve for what a real file holds at most; a longer one grows as its lines arrive.
  v.nodes_.reserve(static_cast<std::size_t>(std::min<long long>(node_count, 1LL << 20)));
  std::vector<int> node_line(1, 0);
  for (long long id = 1; id < node_count; ++id) {
    if (!next_line())
      fail("file ends after " + std::to_string(id - 1) + " of " + std::to_string(node_count - 1) + " node lines");
    std::istringstream r(line);
    long long parent = -1;
    std::string weight_text, hex, rest;
    if (!(r >> parent >> weight_text >> hex) || (r >> rest)) fail("expected \"<parent> <weight> <64 hex digits>\"");
    if (parent < 0 || parent >= id) fail("parent " + std::to_string(parent) + " is not an earlier node");
    if (parent < static_cast<long long>(v.nodes_.back().parent))
      fail("parent ids must not decrease (breadth-first order)");
    char* end = nullptr;
    const double weight = std::strtod(weight_text.c_str(), &end);
    if (end == weight_text.c_str() || *end != '\0' || !std::isfinite(weight) || weight < 0) {
      fail("weight \"" + weight_text + "\" is not a finite non-negative number");
    }
    if (hex.size() != 64) fail("descriptor must have 64 hex digits, found " + std::to_string(hex.size()));
    std::uint8_t bytes[32];
    for (int b = 0; b < 32; ++b) {
      int value = 0;
      for (int h = 0; h < 2; ++h) {
        const char ch = hex[static_cast<std::size_t>(2 * b + h)];
        int digit = -1;
        if (ch >= '0' && ch <= '9') digit = ch - '0';
        if (ch >= 'a' && ch <= 'f') digit = ch - 'a' + 10;
        if (ch >= 'A' && ch <= 'F') digit = ch - 'A' + 10;
        if (digit < 0) fail(std::string("invalid hex digit '") + ch + "' in the descriptor");
        value = 16 * value + digit;
      }
      bytes[b] = static_cast<std::uint8_t>(value);
    }
    Node n;
    n.parent = static_cast<NodeId>(parent);
    n.weight = weight;
    n.centre = descriptor_from_bytes(bytes);
    Node& p = v.nodes_[static_cast<std::size_t>(parent)];
    n.level = p.level + 1;
    if (n.level > v.depth_) fail("node is deeper than depth " + std::to_string(v.depth_));
    if (p.child_count == 0) p.first_child = static_cast<NodeId>(id);
    if (p.first_child + p.child_count != static_cast<NodeId>(id)) fail("children of a node are not consecutive");
    if (static_cast<int>(++p.child_count) > v.branching_) {
      fail("node " + std::to_string(parent) + " has more than branching = " + std::to_string(v.branching_) +
           " children");
    }
    v.nodes_.push_back(n);
    node_line.push_back(line_no);
  }
  if (next_line()) fail("unexpected content after the last node");
  for (std::size_t i = 1; i < v.nodes_.size(); ++i) {
    if (v.nodes_[i].child_count > 0 && v.nodes_[i].weight != 0) {
      line_no = node_line[i];
      fail("inner node " + std::to_string(i) + " has a non-zero weight");
    }
  }
  v.index_words();
  return v;
}

}  // namespace bow
}  // namespace cge
