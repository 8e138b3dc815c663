#include "binloop/place/vlad_vocabulary.h"

#include <gtest/gtest.h>

#include <cmath>

#include "binloop/place/model_file.h"
#include "binloop/place/pq_codebooks.h"
#include "place_test_data.h"
#include "support/test_support.h"

using namespace binloop;
using namespace binloop::test;

namespace {

Desc256 bits(int from, int to) {
  Desc256 d;
  for (int b = from; b < to; ++b) d.setBit(b);
  return d;
}

// `n` VLADs of `words` × `dims` standard normal floats.
std::vector<std::vector<float>> randomVlads(int n, int words, int dims, uint64_t seed) {
  HashRng rng(seed);
  std::vector<std::vector<float>> vlads(n, std::vector<float>(static_cast<size_t>(words) * dims));
  for (auto& v : vlads)
    for (auto& x : v) x = static_cast<float>(rng.normal());
  return vlads;
}

}  // namespace

TEST(Vlad, TwoDescriptorsByHand) {
  // One word trained on equal numbers of a and b sits halfway between them. a and b differ in 16 bits,
  // so a's residual is ±0.5 on those bits and 0 elsewhere; normalised, ±1/4 (= 0.5 / (0.5·sqrt(16))).
  const Desc256 a = bits(0, 24), b = bits(8, 32);  // differ in bits 0-7 and 24-31
  VladParams p;
  p.k = 1;
  const VladVocabulary v = VladVocabulary::train({Descriptors(10, a), Descriptors(10, b)}, p);
  const auto va = v.aggregate({a}).front();
  ASSERT_EQ(va.size(), 256u);
  for (int j = 0; j < 256; ++j) {
    const double expected = (j < 8) ? 0.25 : (j >= 24 && j < 32) ? -0.25 : 0.0;
    EXPECT_NEAR(va[j], expected, 1e-6) << j;  // power 0.5 then L2 keeps ±1/4 on 16 equal entries
  }
  const auto vab = v.aggregate({a, b}).front();
  for (float x : vab) EXPECT_NEAR(x, 0.0, 1e-6);  // the two residuals cancel
  const BinarySignature s = binarizeSigns(va);
  EXPECT_EQ(s[0], 0xFFull);  // exactly the bits where a has 1 and the centre 0.5
  EXPECT_THROW_WITH(v.aggregate({}), PlaceError, "empty descriptor set");
}

TEST(Vlad, HierarchicalVocabularyGivesOneSignaturePerLevel) {
  std::vector<Descriptors> images;
  for (int p = 0; p < 8; ++p) images.push_back(randomPlace(9, p, 100));
  VladParams p;
  p.k = 2;
  p.levels = 2;
  const VladVocabulary v = VladVocabulary::train(images, p);
  ASSERT_EQ(v.levels(), 2);
  EXPECT_EQ(v.wordsAtLevel(1), 2);
  EXPECT_EQ(v.wordsAtLevel(2), 4);
  const auto sig = v.aggregate(images[0]);
  EXPECT_EQ(sig[0].size(), 2u * 256);
  EXPECT_EQ(sig[1].size(), 4u * 256);
  double n = 0;
  for (float x : sig[1]) n += x * x;
  EXPECT_NEAR(n, 1.0, 1e-5);
}

// Two images whose few descriptors fall into one word must not agree on the words that are empty in both:
// an empty word gets coin-flip bits, seeded by the image's own descriptors (real_heldout with 64 words: two
// nearly featureless wallpapers were the closest pair of the whole set before).
TEST(Vlad, EmptyWordsGetCoinFlipsNotAgreement) {
  std::vector<Descriptors> images;
  for (int p = 0; p < 8; ++p) images.push_back(randomPlace(11, p, 200));
  VladParams p;
  p.k = 16;
  const VladVocabulary v = VladVocabulary::train(images, p);
  const Descriptors a(3, images[0][0]), b(3, images[1][0]);  // three copies of one descriptor each
  const auto va = v.aggregate(a).front(), vb = v.aggregate(b).front();
  const BinarySignature plain_a = binarizeSigns(va), plain_b = binarizeSigns(vb);
  const BinarySignature sa = binarizeSigns(va, v.dims(), descriptorSeed(a));
  const BinarySignature sb = binarizeSigns(vb, v.dims(), descriptorSeed(b));
  // At most 2 of 16 words are occupied: plain signs leave >= 14 x 256 bits at 0 in both.
  EXPECT_LE(hammingBits(plain_a, plain_b), 2 * 256);
  // Coin flips: about half of the bits of the empty words differ.
  EXPECT_GT(hammingBits(sa, sb), 14 * 256 * 4 / 10);
  EXPECT_EQ(sa, binarizeSigns(va, v.dims(), descriptorSeed(a))) << "same descriptors, same bits";
  // An occupied word keeps its sign bits.
  int occupied = -1;
  for (int w = 0; w < 16 && occupied < 0; ++w)
    for (int j = 0; j < 256; ++j)
      if (va[w * 256 + j] != 0.f) occupied = w;
  ASSERT_GE(occupied, 0);
  for (int j = 0; j < 256; ++j) {
    const size_t i = static_cast<size_t>(occupied) * 256 + j;
    EXPECT_EQ((sa[i >> 6] >> (i & 63)) & 1u, (plain_a[i >> 6] >> (i & 63)) & 1u) << j;
  }
  // A full image occupies every word: nothing changes.
  const auto full = v.aggregate(images[2]).front();
  EXPECT_EQ(binarizeSigns(full, v.dims(), 5), binarizeSigns(full));
}

// With LCS-PCA each word's residuals are rotated onto their principal directions and whitened (thesis eq.
// 4.6): over the training descriptors of a word, every kept component of the residual's direction has mean
// ~0 and the same share of the length, 1/dims. A one-descriptor image with alpha 1 gives that direction as
// its word's VLAD. A vocabulary read back from its file projects the same.
TEST(Vlad, LcsPcaWhitensResiduals) {
  std::vector<Descriptors> images;
  for (int p = 0; p < 20; ++p) images.push_back(randomPlace(4, p, 100));
  VladParams p;
  p.k = 2;
  p.pca_dims = 32;
  p.alpha = 1;
  const VladVocabulary v = VladVocabulary::train(images, p);
  ASSERT_EQ(v.dims(), 32);
  TempDir dir;
  {
    ModelHeader h;
    h.type = ModelType::kVlad;
    ModelWriter w(h);
    v.write(w);
    w.save(dir / "v.bin");
  }
  ModelReader r(dir / "v.bin");
  const VladVocabulary back = VladVocabulary::read(r);
  std::vector<double> sum(64, 0.0), sum2(64, 0.0);
  int count[2] = {0, 0};
  for (const auto& im : images) {
    for (const auto& d : im) {
      const std::vector<float> u = v.aggregate(Descriptors{d}).front();
      ASSERT_EQ(u.size(), 64u);
      EXPECT_EQ(back.aggregate(Descriptors{d}).front(), u);
      const int word = u[0] != 0.f || u[1] != 0.f ? 0 : 1;
      ++count[word];
      for (int i = 0; i < 32; ++i)
        sum[word * 32 + i] += u[word * 32 + i], sum2[word * 32 + i] += u[word * 32 + i] * u[word * 32 + i];
    }
  }
  for (int word = 0; word < 2; ++word) {
    ASSERT_GE(count[word], 300) << word;
    for (int i = 0; i < 32; ++i) {
      EXPECT_NEAR(sum[word * 32 + i] / count[word], 0.0, 0.03) << "word " << word << " component " << i;
      EXPECT_NEAR(sum2[word * 32 + i] / count[word], 1.0 / 32, 0.5 / 32)
          << "word " << word << " component " << i;
    }
  }
}

// A file whose parameters promise whitened words but that holds no rotation is refused when read (it would
// otherwise write 256 floats a word into 32-float slots); the same file without the promise loads.
TEST(Vlad, AFileThatPromisesPcaWithoutRotationsIsRefused) {
  TempDir dir;
  auto save = [&](float pca_dims, const std::string& name) {
    ModelHeader h;
    h.type = ModelType::kVlad;
    ModelWriter w(h);
    w.section("VPAR", std::vector<float>{0.5f, pca_dims, 2.f, 1.f, 1.f});
    w.section("VCEN", std::vector<float>(2 * 256, 0.5f));
    w.section("VFCH", std::vector<uint32_t>{0, 0, 0});
    w.section("VNCH", std::vector<uint32_t>{2, 0, 0});
    w.section("VLVB", std::vector<uint32_t>{0});
    w.section("VLVC", std::vector<uint32_t>{2});
    w.section("VPCA", std::vector<int8_t>{});
    w.section("VPCS", std::vector<float>{});
    w.section("VPCM", std::vector<float>{});
    w.save(dir / name);
    return dir / name;
  };
  {
    ModelReader plain(save(0, "plain.bin"));
    EXPECT_EQ(VladVocabulary::read(plain).dims(), 256);
  }
  ModelReader promised(save(32, "promised.bin"));
  EXPECT_THROW_WITH(VladVocabulary::read(promised), PlaceError, "VLAD vocabulary sections are inconsistent");
}

TEST(ProductQuantization, SdcAndAdcMatchBruteForce) {
  const int words = 3, dims = 5, m = 4;
  const auto vlads = randomVlads(60, words, dims, 11);
  const PqCodebooks pq = PqCodebooks::train(vlads, words, dims, m, 1);
  for (int t = 0; t < 10; ++t) {
    const auto& a = vlads[t];
    const auto& b = vlads[59 - t];
    const PqCodes ca = pq.encode(a), cb = pq.encode(b);
    double sdc = 0, adc = 0;
    for (int w = 0; w < words; ++w) {
      // Brute force: the nearest centroid by exhaustive search, then plain squared distances.
      int best = 0;
      double bd = 1e30;
      for (int c = 0; c < m; ++c) {
        double d = 0;
        for (int j = 0; j < dims; ++j) d += std::pow(a[w * dims + j] - pq.centroid(w, c)[j], 2);
        if (d < bd) bd = d, best = c;
      }
      EXPECT_EQ(ca[w], best);
      for (int j = 0; j < dims; ++j) {
        sdc += std::pow(pq.centroid(w, ca[w])[j] - pq.centroid(w, cb[w])[j], 2);
        adc += std::pow(a[w * dims + j] - pq.centroid(w, cb[w])[j], 2);
      }
    }
    EXPECT_NEAR(pq.sdc(ca, cb), sdc, 1e-4);
    EXPECT_NEAR(pq.adc(a, cb), adc, 1e-4);
  }
  EXPECT_THROW_WITH(PqCodebooks::train({vlads[0], vlads[0]}, words, dims, m, 1), PlaceError,
                    "degenerate PQ codebook");
}

TEST(ProductQuantization, SixteenBitFileGivesTheTrainedCodesAndOldFloatFilesStillLoad) {
  const int words = 2, dims = 6, m = 4;
  const auto vlads = randomVlads(40, words, dims, 12);
  const PqCodebooks pq = PqCodebooks::train(vlads, words, dims, m, 3);
  TempDir dir;
  ModelHeader h;
  h.type = ModelType::kVladPq;
  {
    ModelWriter w(h);
    pq.write(w);
    w.save((dir / "pq.bin"));
  }
  ModelReader r((dir / "pq.bin"));
  const PqCodebooks back = PqCodebooks::read(r);
  for (int w = 0; w < words; ++w)
    for (int c = 0; c < m; ++c)
      for (int j = 0; j < dims; ++j) EXPECT_EQ(back.centroid(w, c)[j], pq.centroid(w, c)[j]);
  EXPECT_EQ(back.sdc(back.encode(vlads[0]), back.encode(vlads[1])),
            pq.sdc(pq.encode(vlads[0]), pq.encode(vlads[1])));

  // A file written before the 16-bit codebooks: three parameters and the floats themselves.
  std::vector<float> floats;
  for (int w = 0; w < words; ++w)
    for (int c = 0; c < m; ++c) floats.insert(floats.end(), pq.centroid(w, c), pq.centroid(w, c) + dims);
  floats[0] = 0.123456789f;
  {
    ModelWriter w(h);
    w.section("QPAR", std::vector<uint32_t>{uint32_t{words}, uint32_t{dims}, uint32_t{m}});
    w.section("QCBK", floats);
    w.save((dir / "old.bin"));
  }
  ModelReader old((dir / "old.bin"));
  EXPECT_EQ(PqCodebooks::read(old).centroid(0, 0)[0], 0.123456789f);

  {
    ModelWriter w(h);
    w.section("QPAR", std::vector<uint32_t>{uint32_t{words}, uint32_t{dims}, uint32_t{m}, 7});
    w.save((dir / "bad.bin"));
  }
  ModelReader bad((dir / "bad.bin"));
  EXPECT_THROW_WITH(PqCodebooks::read(bad), PlaceError, "PQ parameter section malformed");
}
