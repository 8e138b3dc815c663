#include "binloop/features/brief_pattern_learning.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <tuple>

#include "binloop/features/feature_error.h"
#include "binloop/io/kitti_sequence.h"
#include "binloop/util/hash_random.h"
#include "support/test_support.h"

using namespace binloop;

namespace {

std::string kittiLeftPath(int i) {
  char name[32];
  std::snprintf(name, sizeof name, "%06d.png", i);
  return test::sharedData("kitti/sample_00/image_0/") + name;
}

cv::Mat kittiLeft(int i) { return readGrayImage(kittiLeftPath(i)); }

// learn-pattern samples with binloop's Gaussian extractor (its keypoints, angles and smoothed levels; the
// tests are what it learns), whatever the SLAM's default tests are.
OrbSlamExtractor gaussianExtractor() {
  OrbSlamParams p;
  p.pattern = BriefPatternKind::kGaussian;
  return OrbSlamExtractor(p);
}

bool bit(const Desc256& d, int i) { return (d.w[i / 64] >> (i % 64)) & 1; }

}  // namespace

TEST(BriefPattern, TestsStayInsideTheDiscAndAreDistinct) {
  std::set<std::tuple<int, int, int, int>> seen;
  for (const BriefTest& t : briefPattern()) {
    EXPECT_LE(t.ax * t.ax + t.ay * t.ay, 225);
    EXPECT_LE(t.bx * t.bx + t.by * t.by, 225);
    EXPECT_FALSE(t.ax == t.bx && t.ay == t.by);
    EXPECT_TRUE(seen.insert({t.ax, t.ay, t.bx, t.by}).second);
    EXPECT_EQ(seen.count({t.bx, t.by, t.ax, t.ay}), 0u);
  }
  EXPECT_EQ(briefDisc().size(), 709u);
}

// Tests learned on some real KITTI frames are balanced on others, unlike the extractor's Gaussian pattern
// (mean |P(1) - 0.5| about 0.2 on such frames).
TEST(BriefPatternLearning, LearnedTestsAreBalancedOnHeldOutFrames) {
  BINLOOP_REQUIRE_DATA(kittiLeftPath(10));  // frames 0-10 of the real sample
  const OrbSlamExtractor ex = gaussianExtractor();
  PatchSamples train, held_out;
  for (int i : {0, 2, 4, 6}) train.append(samplePatches(kittiLeft(i), ex, 1000, i));
  for (int i : {8, 10}) held_out.append(samplePatches(kittiLeft(i), ex, 100000, i));
  PatternLearningOptions o;
  o.bits = 64;
  o.pool = 4000;
  const LearnedPattern lp = learnBriefPattern(train, o);
  ASSERT_EQ(lp.tests.size(), 64u);
  auto bias = [&](const BriefTest& t) {
    double ones = 0;
    for (uint8_t x : testBits(held_out, t)) ones += x;
    return std::abs(ones / held_out.keypoints() - 0.5);
  };
  double learned = 0, gaussian = 0;
  for (int b = 0; b < 64; ++b) {
    learned += bias(lp.tests[b]) / 64;
    gaussian += bias(briefPattern()[b]) / 64;
    EXPECT_GE(std::max(std::abs(lp.tests[b].ax - lp.tests[b].bx), std::abs(lp.tests[b].ay - lp.tests[b].by)),
              o.min_separation);
  }
  EXPECT_LT(learned, 0.06);
  EXPECT_GT(gaussian, learned + 0.1);
}

// samplePatches reads what the extractor reads: the Gaussian pattern's tests on the samples are the bits of
// the extractor's descriptors with that pattern.
TEST(BriefPatternLearning, SamplesGiveTheExtractorsBits) {
  BINLOOP_REQUIRE_DATA(kittiLeftPath(10));          // frames 0-10 of the real sample
  const OrbSlamExtractor ex = gaussianExtractor();  // the tests briefPattern() holds
  const cv::Mat img = kittiLeft(0);
  const OrbFeatures f = ex.extract(img);
  const PatchSamples s = samplePatches(img, ex, 1000000, 1);
  ASSERT_EQ(s.keypoints(), f.descriptors.size());
  size_t differ = 0;
  for (int b = 0; b < 256; ++b) {
    const std::vector<uint8_t> bits = testBits(s, briefPattern()[b]);
    for (size_t k = 0; k < bits.size(); ++k) differ += bits[k] != bit(f.descriptors[k], b);
  }
  EXPECT_EQ(differ, 0u);
  // A sample of them is a seeded subset, in extraction order.
  const PatchSamples few = samplePatches(img, ex, 100, 7);
  ASSERT_EQ(few.keypoints(), 100u);
  EXPECT_EQ(samplePatches(img, ex, 100, 7).values, few.values);
  EXPECT_NE(samplePatches(img, ex, 100, 8).values, few.values);
}

TEST(BriefPatternLearning, DeterministicBalancedAndDecorrelatedOnATinyInput) {
  BINLOOP_REQUIRE_DATA(kittiLeftPath(10));  // frames 0-10 of the real sample
  const OrbSlamExtractor ex = gaussianExtractor();
  PatchSamples s;
  for (int i : {0, 10}) s.append(samplePatches(kittiLeft(i)(cv::Rect(300, 0, 500, 376)).clone(), ex, 400, i));
  ASSERT_EQ(s.keypoints(), 800u);
  PatternLearningOptions o;
  o.bits = 32;
  o.pool = 3000;
  const LearnedPattern a = learnBriefPattern(s, o);
  const LearnedPattern b = learnBriefPattern(s, o);
  ASSERT_EQ(a.tests.size(), 32u);
  ASSERT_EQ(b.tests.size(), 32u);
  for (size_t i = 0; i < a.tests.size(); ++i) {
    EXPECT_EQ(std::tie(a.tests[i].ax, a.tests[i].ay, a.tests[i].bx, a.tests[i].by),
              std::tie(b.tests[i].ax, b.tests[i].ay, b.tests[i].bx, b.tests[i].by));
    EXPECT_NEAR(a.mean[i], 0.5, 0.05);
    // The reported mean is the test's mean on the samples.
    const auto bits = testBits(s, a.tests[i]);
    double ones = 0;
    for (uint8_t x : bits) ones += x;
    EXPECT_DOUBLE_EQ(ones / bits.size(), a.mean[i]);
  }
  EXPECT_EQ(a.threshold, b.threshold);
  EXPECT_LT(a.max_abs_correlation, a.threshold);
  EXPECT_LE(a.walked, o.pool);
  // Thread count changes nothing.
  o.threads = 1;
  const LearnedPattern c = learnBriefPattern(s, o);
  for (size_t i = 0; i < a.tests.size(); ++i) EXPECT_EQ(a.tests[i].bx, c.tests[i].bx);
  EXPECT_THROW(learnBriefPattern(PatchSamples{}, o), FeatureError);
}
