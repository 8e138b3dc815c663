#include "binloop/place/dbow2_import.h"

#include <gtest/gtest.h>

#include "binloop/place/model_training.h"
#include "support/test_support.h"

using namespace binloop;
using namespace binloop::test;

TEST(Dbow2Import, ReadsTheRealYamlVocabulary) {
  const std::string voc = sharedData("vocab/dbow2_orb_small_voc.yml.gz");
  BINLOOP_REQUIRE_DATA(voc);
  const VocabularyTree t = importDbow2(voc);
  EXPECT_EQ(t.k(), 9);
  EXPECT_EQ(t.levels(), 3);
  EXPECT_EQ(t.words(), 692u);
  EXPECT_EQ(t.weighting(), Weighting::kTfIdf);
  for (uint32_t w : {0u, 100u, 691u}) EXPECT_EQ(t.wordOf(t.wordDescriptor(w)), w);
  // Survives our own format.
  TempDir dir;
  saveHbowModel(t, {}, dir / "voc.bin");
  ModelReader r(dir / "voc.bin");
  EXPECT_EQ(r.header().words, 692u);
}

TEST(Dbow2Import, ReadsOrbSlamTextFormat) {
  TempDir dir;
  std::string a = "0 0", b = "0 1";
  for (int i = 0; i < 32; ++i) a += " 0", b += " 255";
  // Root's two children: node 1 (inner, all zeros) and node 2 (word, all ones); node 3 a word under 1.
  std::string c = "1 1";
  for (int i = 0; i < 32; ++i) c += i == 0 ? " 1" : " 0";
  writeText(dir / "voc.txt", "2 2 0 0\n" + a + " 0\n" + b + " 0.7\n" + c + " 0.3\n");
  const VocabularyTree t = importDbow2(dir / "voc.txt");
  EXPECT_EQ(t.words(), 2u);
  Desc256 ones;
  for (auto& w : ones.w) w = ~uint64_t{0};
  EXPECT_FLOAT_EQ(t.weight(t.wordOf(ones)), 0.7f);
  EXPECT_FLOAT_EQ(t.weight(t.wordOf(Desc256{})), 0.3f);
}

TEST(Dbow2Import, MalformedTextNamesTheLine) {
  TempDir dir;
  writeText(dir / "short.txt", "10 6 0 0\n0 0 1 2 3\n");
  EXPECT_THROW_WITH(importDbow2(dir / "short.txt"), PlaceError,
                    "short.txt:2: node: descriptor needs 32 byte values");
  writeText(dir / "head.txt", "ten six\n");
  EXPECT_THROW_WITH(importDbow2(dir / "head.txt"), PlaceError,
                    "head.txt:1: expected 'k L scoring weighting'");
  EXPECT_THROW_WITH(importDbow2(dir / "missing.yml.gz"), PlaceError, "cannot open");
}
