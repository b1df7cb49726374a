// Tests of the bag-of-words core (cge/bow): descriptors, vocabulary training and descent, tf-idf,
// the L1 score, the inverted-index database, persistence and determinism. Oracles: bit-by-bit
// Hamming distance, exhaustive nearest-word search, hand-worked tf-idf and scores, brute-force
// scoring of every database entry.

#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "cge/bow/binary_descriptor.hpp"
#include "cge/bow/bow_vector.hpp"
#include "cge/bow/database.hpp"
#include "cge/bow/vocabulary.hpp"
#include "temp_dir.hpp"
#include "test_support.hpp"

using cge::bow::BinaryDescriptor;
using cge::bow::BowVector;
using cge::bow::Vocabulary;
using cge::bow::VocabularySettings;

namespace {

BinaryDescriptor random_descriptor(std::mt19937_64& rng) { return {rng(), rng(), rng(), rng()}; }

int hamming_oracle(const BinaryDescriptor& a, const BinaryDescriptor& b) {
  int n = 0;
  for (int j = 0; j < 256; ++j) n += cge::bow::descriptor_bit(a, j) != cge::bow::descriptor_bit(b, j);
  return n;
}

/// `flips` distinct random bits of d flipped.
BinaryDescriptor flip_bits(BinaryDescriptor d, int flips, std::mt19937_64& rng) {
  std::vector<int> bits(256);
  for (int i = 0; i < 256; ++i) bits[static_cast<std::size_t>(i)] = i;
  for (int i = 0; i < flips; ++i) {
    const std::size_t j =
        static_cast<std::size_t>(i) + static_cast<std::size_t>(rng() % static_cast<std::uint64_t>(256 - i));
    std::swap(bits[static_cast<std::size_t>(i)], bits[j]);
    const int b = bits[static_cast<std::size_t>(i)];
    d[static_cast<std::size_t>(b / 64)] ^= std::uint64_t{1} << (b % 64);
  }
  return d;
}

std::vector<std::vector<BinaryDescriptor>> random_images(int images, int per_image, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<std::vector<BinaryDescriptor>> out(static_cast<std::size_t>(images));
  for (auto& img : out)
    for (int i = 0; i < per_image; ++i) img.push_back(random_descriptor(rng));
  return out;
}

Vocabulary train(const std::vector<std::vector<BinaryDescriptor>>& images, int k, int depth, std::uint64_t seed,
                 int iterations = 10) {
  VocabularySettings s;
  s.branching = k;
  s.depth = depth;
  s.max_iterations = iterations;
  std::mt19937_64 engine(seed);
  return Vocabulary::train(images, s, engine);
}

std::size_t exhaustive_nearest_word(const Vocabulary& v, const BinaryDescriptor& q) {
  std::size_t best = 0;
  int best_d = 1000;
  for (std::size_t w = 0; w < v.word_count(); ++w) {
    const int d = cge::bow::hamming_distance(q, v.nodes()[v.word_node(static_cast<cge::bow::WordId>(w))].centre);
    if (d < best_d) {
      best_d = d;
      best = w;
    }
  }
  return best;
}

std::string saved(const Vocabulary& v) {
  std::ostringstream out;
  v.save(out);
  return out.str();
}

std::string load_error(const std::string& text) {
  return cge_test::invalid_argument_message([&] {
    std::istringstream in(text);
    Vocabulary::load(in, "vocab.txt");
  });
}

}  // namespace

TEST_CASE("BinaryDescriptor: Hamming distance and byte order against bit-by-bit oracles", "[bow]") {
  std::mt19937_64 rng(11);
  for (int t = 0; t < 200; ++t) {
    const BinaryDescriptor a = random_descriptor(rng);
    const BinaryDescriptor b = random_descriptor(rng);
    CHECK(cge::bow::hamming_distance(a, b) == hamming_oracle(a, b));
    std::uint8_t bytes[32];
    for (int i = 0; i < 32; ++i) bytes[i] = static_cast<std::uint8_t>(rng());
    const BinaryDescriptor d = cge::bow::descriptor_from_bytes(bytes);
    for (int j = 0; j < 256; ++j) REQUIRE(cge::bow::descriptor_bit(d, j) == (((bytes[j / 8] >> (j % 8)) & 1) != 0));
    for (int i = 0; i < 32; ++i) REQUIRE(cge::bow::descriptor_byte(d, i) == bytes[i]);
    std::uint8_t other[32];
    for (int i = 0; i < 32; ++i) other[i] = static_cast<std::uint8_t>(rng());
    CHECK(cge::bow::hamming_distance_32_bytes(bytes, other) ==
          hamming_oracle(d, cge::bow::descriptor_from_bytes(other)));
  }
  // The extremes: equal rows, and complementary rows (every bit differs).
  std::uint8_t zeros[32] = {}, ones[32];
  for (std::uint8_t& b : ones) b = 0xff;
  CHECK(cge::bow::hamming_distance_32_bytes(zeros, zeros) == 0);
  CHECK(cge::bow::hamming_distance_32_bytes(zeros, ones) == 256);
}

TEST_CASE("Vocabulary: flat tree descent equals the exhaustive nearest word", "[bow]") {
  const auto images = random_images(8, 100, 3);
  const Vocabulary v = train(images, 16, 1, 5);
  REQUIRE(v.word_count() == 16);
  std::mt19937_64 rng(99);
  for (int t = 0; t < 500; ++t) {
    const BinaryDescriptor q = random_descriptor(rng);
    CHECK(v.word_of(q) == exhaustive_nearest_word(v, q));
  }
}

TEST_CASE("Vocabulary: descent finds the nearest leaf when clusters are well separated", "[bow]") {
  // 4 top prototypes, 4 sub-prototypes each (24 bits away), members 3 bits from their sub-prototype:
  // the tree must recover the 16 clusters and descent must agree with the exhaustive search.
  std::mt19937_64 rng(7);
  std::vector<std::vector<BinaryDescriptor>> images(4);
  std::vector<BinaryDescriptor> queries;
  for (int top = 0; top < 4; ++top) {
    const BinaryDescriptor proto = random_descriptor(rng);
    for (int sub = 0; sub < 4; ++sub) {
      const BinaryDescriptor sp = flip_bits(proto, 24, rng);
      for (int m = 0; m < 20; ++m) images[static_cast<std::size_t>(m % 4)].push_back(flip_bits(sp, 3, rng));
      for (int m = 0; m < 5; ++m) queries.push_back(flip_bits(sp, 4, rng));
    }
  }
  const Vocabulary v = train(images, 4, 2, 1, 100);
  CHECK(v.word_count() == 16);
  for (const BinaryDescriptor& q : queries) CHECK(v.word_of(q) == exhaustive_nearest_word(v, q));
}

TEST_CASE("Vocabulary: structure, greedy descent and majority-bit centres on random descriptors", "[bow]") {
  const auto images = random_images(10, 200, 17);
  const int k = 5, depth = 3;
  const Vocabulary v = train(images, k, depth, 23, 1000);
  const auto& nodes = v.nodes();
  std::size_t leaves = 0;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    CHECK(nodes[i].child_count <= static_cast<std::uint32_t>(k));
    CHECK(nodes[i].level <= depth);
    if (i > 0) CHECK(nodes[nodes[i].parent].level + 1 == nodes[i].level);
    if (nodes[i].child_count == 0 && i > 0) ++leaves;
  }
  CHECK(leaves == v.word_count());
  CHECK(v.word_count() > static_cast<std::size_t>(k * k));  // 2000 random descriptors fill the tree
  // Descent oracle: at every step the chosen child is the nearest sibling (first on ties).
  std::mt19937_64 rng(5);
  for (int t = 0; t < 200; ++t) {
    const BinaryDescriptor q = random_descriptor(rng);
    cge::bow::NodeId n = 0;
    while (nodes[n].child_count > 0) {
      cge::bow::NodeId best = nodes[n].first_child;
      for (cge::bow::NodeId c = nodes[n].first_child; c < nodes[n].first_child + nodes[n].child_count; ++c) {
        if (hamming_oracle(q, nodes[c].centre) < hamming_oracle(q, nodes[best].centre)) best = c;
      }
      n = best;
    }
    CHECK(v.word_of(q) == static_cast<cge::bow::WordId>(nodes[n].word));
  }
  // Converged k-medians on the first level: each root child's centre is the majority bit of the
  // training descriptors that descend into it.
  std::vector<std::vector<int>> ones(nodes[0].child_count, std::vector<int>(256, 0));
  std::vector<int> count(nodes[0].child_count, 0);
  for (const auto& img : images) {
    for (const auto& d : img) {
      const cge::bow::NodeId c = v.descend(d, 1) - nodes[0].first_child;
      ++count[c];
      for (int j = 0; j < 256; ++j) ones[c][static_cast<std::size_t>(j)] += cge::bow::descriptor_bit(d, j);
    }
  }
  for (std::uint32_t c = 0; c < nodes[0].child_count; ++c) {
    const auto& centre = nodes[nodes[0].first_child + c].centre;
    for (int j = 0; j < 256; ++j) {
      REQUIRE(cge::bow::descriptor_bit(centre, j) == (2 * ones[c][static_cast<std::size_t>(j)] > count[c]));
    }
  }
}

TEST_CASE("Vocabulary: tf-idf weights and the L1 score, hand-worked", "[bow]") {
  // Three distinct descriptors A, B, C (fewer than k: one leaf each, words 0, 1, 2 in order of
  // first appearance). Images {A, A, B}, {B, C}, {B}: n_A = 1, n_B = 3, n_C = 1 of N = 3.
  std::mt19937_64 rng(1);
  const BinaryDescriptor A = random_descriptor(rng), B = random_descriptor(rng), C = random_descriptor(rng);
  const Vocabulary v = train({{A, A, B}, {B, C}, {B}}, 10, 3, 1);
  REQUIRE(v.word_count() == 3);
  CHECK(v.word_of(A) == 0);
  CHECK(v.word_of(B) == 1);
  CHECK(v.word_of(C) == 2);
  CHECK(v.word_weight(0) == Approx(std::log(3.0)));
  CHECK(v.word_weight(1) == 0.0);
  CHECK(v.word_weight(2) == Approx(std::log(3.0)));
  // {A, A, B, C}: tf-idf A 2 ln 3, B 0 (left out), C ln 3; normalised 2/3, 1/3.
  const BowVector a = v.transform({A, A, B, C});
  REQUIRE(a.size() == 2);
  CHECK(a[0].word == 0);
  CHECK(a[0].weight == Approx(2.0 / 3));
  CHECK(a[1].word == 2);
  CHECK(a[1].weight == Approx(1.0 / 3));
  // s = 1 - 0.5 (|2/3 - 1/2| + 1/4 + |1/3 - 1/4|) = 1 - 0.5 * 0.5 = 0.75, normalised or not.
  const BowVector b = {{0, 0.5}, {1, 0.25}, {2, 0.25}};
  CHECK(cge::bow::l1_score(a, b) == Approx(0.75));
  CHECK(cge::bow::l1_score({{0, 4.0}, {2, 2.0}}, {{0, 2.0}, {1, 1.0}, {2, 1.0}}) == Approx(0.75));
  CHECK(cge::bow::l1_score(a, a) == Approx(1.0));
  CHECK(cge::bow::l1_score(a, {{1, 1.0}}) == 0.0);
  CHECK(cge::bow::l1_score(a, {}) == 0.0);
  CHECK(cge::bow::common_words(a, b) == 2);
  // Direct index at level 1: the words are the level-1 nodes.
  cge::bow::FeatureVector fv;
  v.transform({A, C, A}, &fv, 1);
  REQUIRE(fv.size() == 2);
  CHECK(fv.at(v.word_node(0)) == std::vector<int>{0, 2});
  CHECK(fv.at(v.word_node(2)) == std::vector<int>{1});
}

TEST_CASE("BowDatabase: common words and scores equal brute force over every entry", "[bow]") {
  std::mt19937_64 rng(31);
  auto random_vector = [&]() {
    BowVector v;
    for (cge::bow::WordId w = 0; w < 60; ++w) {
      if (rng() % 4 == 0) v.push_back({w, 0.1 + static_cast<double>(rng() % 100)});
    }
    return v;
  };
  cge::bow::BowDatabase db;
  std::vector<BowVector> stored;
  for (int i = 0; i < 40; ++i) {
    stored.push_back(random_vector());
    CHECK(db.add(stored.back()) == i);
  }
  stored.push_back({});  // an empty entry never matches
  CHECK(db.add({}) == 40);
  for (int t = 0; t < 20; ++t) {
    const BowVector q = random_vector();
    const auto result = db.query(q);
    std::size_t r = 0;
    for (std::size_t i = 0; i < stored.size(); ++i) {
      const int common = cge::bow::common_words(q, stored[i]);
      if (common == 0) continue;
      REQUIRE(r < result.size());
      CHECK(result[r].entry == static_cast<int>(i));
      CHECK(result[r].common_words == common);
      CHECK(result[r].score == Approx(cge::bow::l1_score(q, stored[i])).margin(1e-12));
      ++r;
    }
    CHECK(r == result.size());
  }
  CHECK_THROWS_AS(db.add({{3, 1.0}, {2, 1.0}}), std::invalid_argument);
  CHECK_THROWS_AS(db.query({{3, -1.0}}), std::invalid_argument);
}

TEST_CASE("Vocabulary: save and load round trip, files not overwritten", "[bow]") {
  const Vocabulary v = train(random_images(6, 150, 41), 6, 3, 2);
  const std::string text = saved(v);
  std::istringstream in(text);
  const Vocabulary back = Vocabulary::load(in);
  CHECK(back == v);
  CHECK(saved(back) == text);
  std::mt19937_64 rng(8);
  std::vector<BinaryDescriptor> q;
  for (int i = 0; i < 100; ++i) q.push_back(random_descriptor(rng));
  const BowVector a = v.transform(q), b = back.transform(q);
  REQUIRE(a.size() == b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    CHECK(a[i].word == b[i].word);
    CHECK(a[i].weight == b[i].weight);
  }

  cge_test::TempDir dir("cge_bow");
  const std::string path = dir.file("voc.txt");
  v.save_file(path);
  CHECK(Vocabulary::load_file(path) == v);
  { std::ofstream(dir.file("mine.txt")) << "user data\n"; }
  CHECK_THROWS_WITH(v.save_file(dir.file("mine.txt")), Catch::Contains("exists"));
  std::ifstream kept(dir.file("mine.txt"));
  std::string line;
  std::getline(kept, line);
  CHECK(line == "user data");
  v.save_file(dir.file("mine.txt"), true);
  CHECK(Vocabulary::load_file(dir.file("mine.txt")) == v);
  CHECK_THROWS_WITH(Vocabulary::load_file(dir.file("absent.txt")), Catch::Contains("absent.txt"));
}

TEST_CASE("Vocabulary: malformed files give errors naming the line", "[bow]") {
  const std::string hex(64, 'a');
  const std::string header = "CGE_VOCABULARY 1\nbranching 2 depth 2 training_images 3 nodes 3\n";
  // A good minimal file first (so that the errors below come from the one change each makes).
  {
    std::istringstream in(header + "0 0.5 " + hex + "\n0 0 " + std::string(64, 'b') + "\n");
    const Vocabulary v = Vocabulary::load(in);
    CHECK(v.word_count() == 2);
  }
  CHECK_THAT(load_error(""), Catch::Contains("vocab.txt:1") && Catch::Contains("empty"));
  CHECK_THAT(load_error("DBOW2\n"), Catch::Contains("vocab.txt:1") && Catch::Contains("not a cge vocabulary"));
  CHECK_THAT(load_error("CGE_VOCABULARY 2\n"), Catch::Contains("vocab.txt:1") && Catch::Contains("version 2"));
  CHECK_THAT(load_error("CGE_VOCABULARY 1\nbranching 2 depth 2\n"), Catch::Contains("vocab.txt:2"));
  CHECK_THAT(load_error("CGE_VOCABULARY 1\nbranching 1 depth 2 training_images 3 nodes 3\n"),
             Catch::Contains("vocab.txt:2") && Catch::Contains("branching"));
  CHECK_THAT(load_error(header + "0 0.5 " + hex + "\n"), Catch::Contains("ends after 1 of 2"));
  // A node count the tree cannot hold (found by fuzzing: it reserved 35 GB before reading a node).
  CHECK_THAT(load_error("CGE_VOCABULARY 1\nbranching 3 depth 2 training_images 2 nodes 554042618\n0 0 " + hex + "\n"),
             Catch::Contains("vocab.txt:2") && Catch::Contains("exceeds the 13 nodes"));
  {
    // The largest count the shape allows is accepted as far as the header goes.
    std::istringstream in("CGE_VOCABULARY 1\nbranching 2 depth 1 training_images 3 nodes 3\n0 0.5 " + hex + "\n0 0 " +
                          std::string(64, 'b') + "\n");
    CHECK(Vocabulary::load(in).word_count() == 2);
  }
  CHECK_THAT(load_error(header + "0 0.5 " + hex + "\n0 0.5 " + hex.substr(2) + "\n"),
             Catch::Contains("vocab.txt:4") && Catch::Contains("64 hex digits"));
  CHECK_THAT(load_error(header + "0 0.5 " + hex + "\n0 0.5 " + std::string(63, 'a') + "g\n"),
             Catch::Contains("vocab.txt:4") && Catch::Contains("invalid hex digit 'g'"));
  CHECK_THAT(load_error(header + "0 -1 " + hex + "\n0 0.5 " + hex + "\n"),
             Catch::Contains("vocab.txt:3") && Catch::Contains("weight"));
  CHECK_THAT(load_error(header + "0 0.5 " + hex + "\n2 0.5 " + hex + "\n"),
             Catch::Contains("vocab.txt:4") && Catch::Contains("not an earlier node"));
  CHECK_THAT(load_error(header + "0 0.5 " + hex + "\n0 0.5 " + hex + "\nextra\n"),
             Catch::Contains("vocab.txt:5") && Catch::Contains("unexpected content"));
  CHECK_THAT(load_error("CGE_VOCABULARY 1\nbranching 2 depth 2 training_images 3 nodes 4\n0 0 " + hex + "\n0 0 " + hex +
                        "\n0 0 " + hex + "\n"),
             Catch::Contains("vocab.txt:5") && Catch::Contains("more than branching"));
  CHECK_THAT(
      load_error("CGE_VOCABULARY 1\nbranching 2 depth 1 training_images 3 nodes 3\n0 0 " + hex + "\n1 0 " + hex + "\n"),
      Catch::Contains("vocab.txt:4") && Catch::Contains("deeper than depth 1"));
  CHECK_THAT(
      load_error("CGE_VOCABULARY 1\nbranching 2 depth 2 training_images 3 nodes 3\n0 1 " + hex + "\n1 0 " + hex + "\n"),
      Catch::Contains("vocab.txt:3") && Catch::Contains("inner node 1"));
}

TEST_CASE("Vocabulary: training is deterministic in the seed", "[bow]") {
  const auto images = random_images(5, 300, 77);
  const Vocabulary a = train(images, 8, 3, 1234);
  const Vocabulary b = train(images, 8, 3, 1234);
  CHECK(a == b);
  CHECK(saved(a) == saved(b));
  // The seed is used: another one seeds other centres on random data.
  CHECK(train(images, 8, 3, 4321) != a);
  CHECK_THROWS_AS(train({{}, {}}, 8, 3, 1), std::invalid_argument);
  CHECK_THROWS_AS(train(images, 1, 3, 1), std::invalid_argument);
}
