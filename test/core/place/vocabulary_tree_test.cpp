#include "binloop/place/vocabulary_tree.h"

#include <gtest/gtest.h>

#include <fstream>
#include <map>

#include "binloop/place/dbow2_import.h"
#include "binloop/place/hbow_recognizer.h"
#include "binloop/place/model_training.h"
#include "binloop/util/hash_random.h"
#include "place_test_data.h"
#include "support/test_support.h"

using namespace binloop;
using namespace binloop::test;

namespace {

Desc256 bits(int from, int to) {  // descriptor with bits [from, to) set
  Desc256 d;
  for (int b = from; b < to; ++b) d.setBit(b);
  return d;
}

// k = 2, L = 2: root → {A = no bits, B = all bits}; A → {A1, A2}, B → {B1, B2}.
VocabularyTree handTree() {
  std::vector<VocabularyTree::InputNode> n{{0, Desc256{}, false, 0},     {0, bits(0, 0), false, 0},
                                           {0, bits(0, 256), false, 0},  {1, bits(0, 8), true, 1.0f},
                                           {1, bits(8, 16), true, 2.0f}, {2, bits(0, 248), true, 3.0f},
                                           {2, bits(8, 256), true, 4.0f}};
  return VocabularyTree::fromNodes(2, 2, Weighting::kTfIdf, n);
}

}  // namespace

TEST(VocabularyTree, DescriptorEqualToAWordLandsOnThatWord) {
  const VocabularyTree t = handTree();
  ASSERT_EQ(t.words(), 4u);
  for (uint32_t w = 0; w < t.words(); ++w) {
    BowVector bow;
    t.transform({t.wordDescriptor(w)}, &bow);
    ASSERT_EQ(bow.size(), 1u);
    EXPECT_EQ(bow[0].word, w);
    EXPECT_FLOAT_EQ(bow[0].value, 1.0f);  // L1-normalised
  }
  EXPECT_EQ(t.wordOf(bits(8, 16)), t.wordOf(bits(9, 16)));  // one bit away stays on the word
}

TEST(VocabularyTree, TfIdfWeightsAreNormalisedPerImage) {
  const VocabularyTree t = handTree();
  BowVector bow;
  // Two features on the weight-1 word, one on the weight-4 word: 2·1 and 1·4, normalised → 1/3, 2/3.
  t.transform({bits(0, 8), bits(0, 8), bits(8, 256)}, &bow);
  ASSERT_EQ(bow.size(), 2u);
  EXPECT_NEAR(bow[0].value, 1.0 / 3, 1e-6);
  EXPECT_NEAR(bow[1].value, 2.0 / 3, 1e-6);
}

TEST(BowVector, L1ScoreByHand) {
  const BowVector a{{1, 0.5f}, {2, 0.5f}}, b{{2, 0.5f}, {3, 0.5f}};
  EXPECT_NEAR(l1Score(a, b), 0.5, 1e-9);  // 1 - |a - b|_1 / 2 = 1 - (0.5 + 0 + 0.5) / 2
  EXPECT_NEAR(l1Score(a, a), 1.0, 1e-9);
  EXPECT_NEAR(l1Score(a, BowVector{{7, 1.0f}}), 0.0, 1e-9);
}

TEST(VocabularyTree, TrainingIsSeededAndSurvivesSaveAndLoad) {
  std::vector<Descriptors> images;
  for (int p = 0; p < 20; ++p) images.push_back(randomPlace(1, p, 100));
  VocabTreeParams p;
  p.k = 5;
  p.levels = 3;
  TempDir dir;
  for (const char* name : {"a.bin", "b.bin"}) saveHbowModel(VocabularyTree::train(images, p), {}, dir / name);
  p.seed = 2;
  saveHbowModel(VocabularyTree::train(images, p), {}, dir / "c.bin");
  auto bytes = [](const std::string& f) {
    std::ifstream s(f, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(s), {});
  };
  EXPECT_EQ(bytes(dir / "a.bin"), bytes(dir / "b.bin"));
  EXPECT_NE(bytes(dir / "a.bin"), bytes(dir / "c.bin"));

  const auto trained = VocabularyTree::train(images, VocabTreeParams{5, 3});
  const auto loaded = HbowRecognizer::loadVocabulary(dir / "a.bin");
  EXPECT_EQ(loaded->words(), trained.words());
  EXPECT_GT(trained.words(), 60u);
  BowVector x, y;
  trained.transform(images[3], &x);
  loaded->transform(images[3], &y);
  ASSERT_EQ(x.size(), y.size());
  for (size_t i = 0; i < x.size(); ++i) {
    EXPECT_EQ(x[i].word, y[i].word);
    EXPECT_EQ(x[i].value, y[i].value);
  }
}

TEST(VocabularyTree, RefusesTooFewDescriptors) {
  EXPECT_THROW_WITH(VocabularyTree::train({randomPlace(1, 0, 30)}, VocabTreeParams{10, 6}), PlaceError,
                    "too few descriptors to train a k=10 vocabulary tree: 30 (need at least 100)");
}

// transform() descends 16 descriptors at a time; it must give exactly what one-at-a-time wordOf gives,
// including for leaves above the deepest level (DBoW2's small vocabulary has 692 of 729 possible words)
// and a descriptor count that leaves a partial batch.
TEST(VocabularyTree, BatchedTransformAgreesWithWordOf) {
  const std::string voc = sharedData("vocab/dbow2_orb_small_voc.yml.gz");
  BINLOOP_REQUIRE_DATA(voc);
  const VocabularyTree t = importDbow2(voc);
  HashRng rng(11);
  Descriptors d(37);
  for (auto& x : d)
    for (auto& w : x.w) w = rng.next();
  for (int depth : {0, 1, 2, 3, 5}) {
    BowVector bow;
    FeatureVector fv;
    t.transform(d, &bow, &fv, depth);
    std::map<uint32_t, std::vector<uint32_t>> expected_fv;
    std::map<uint32_t, int> expected_count;
    for (uint32_t i = 0; i < d.size(); ++i) {
      uint32_t node = 0;
      expected_count[t.wordOf(d[i], depth, &node)]++;
      expected_fv[node].push_back(i);
    }
    ASSERT_EQ(fv.size(), expected_fv.size()) << "depth " << depth;
    for (const auto& [node, feats] : fv) {
      EXPECT_EQ(feats, expected_fv[node]) << "depth " << depth;
    }
    std::map<uint32_t, int> got;
    for (const auto& e : bow) got[e.word] = 1;
    for (const auto& [w, c] : expected_count) {
      if (t.weight(w) <= 0) continue;  // zero-weight words are dropped from the BoW vector
      EXPECT_TRUE(got.count(w)) << "word " << w;
    }
  }
}
