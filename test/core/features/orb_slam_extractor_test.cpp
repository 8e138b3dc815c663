#include "binloop/features/orb_slam_extractor.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "binloop/features/descriptor_statistics.h"
#include "binloop/features/feature_error.h"
#include "binloop/io/kitti_sequence.h"
#include "binloop/util/hash_random.h"
#include "binloop/util/median.h"
#include "support/test_support.h"

using namespace binloop;

namespace {

std::string kittiLeft(int i) {
  char name[32];
  std::snprintf(name, sizeof name, "%06d.png", i);
  return test::sharedData("kitti/sample_00/image_0/") + name;
}

// Share of a 16x6 grid's cells holding at least one keypoint.
double gridCoverage(const std::vector<cv::KeyPoint>& kps, cv::Size size) {
  std::vector<char> cells(96, 0);
  for (const auto& k : kps)
    cells[std::min(5, static_cast<int>(k.pt.y * 6 / size.height)) * 16 +
          std::min(15, static_cast<int>(k.pt.x * 16 / size.width))] = 1;
  return std::count(cells.begin(), cells.end(), 1) / 96.0;
}

// Signed difference b - a of two angles in degrees, in (-180, 180].
double angleDiff(double a, double b) {
  double d = std::fmod(b - a, 360.0);
  if (d <= -180) d += 360;
  if (d > 180) d -= 360;
  return d;
}

// Pairs of keypoints that see the same scene point: for each keypoint of `a` (within `radius` of `centre`
// when radius > 0), the keypoint of `b` at octave + `octave_shift` nearest to where `a_to_b` maps it, if
// within 1.5 pixels of that octave.
struct Pair {
  int a, b;
};
std::vector<Pair> samePoints(const OrbFeatures& a, const OrbFeatures& b, const cv::Matx23d& a_to_b,
                             int octave_shift, cv::Point2f centre = {}, float radius = 0) {
  std::vector<Pair> pairs;
  for (int i = 0; i < static_cast<int>(a.keypoints.size()); ++i) {
    const auto& ka = a.keypoints[i];
    if (radius > 0 && cv::norm(ka.pt - centre) > radius) continue;
    const cv::Point2f q(a_to_b(0, 0) * ka.pt.x + a_to_b(0, 1) * ka.pt.y + a_to_b(0, 2),
                        a_to_b(1, 0) * ka.pt.x + a_to_b(1, 1) * ka.pt.y + a_to_b(1, 2));
    const float tol = 1.5f * std::pow(1.2f, static_cast<float>(ka.octave + octave_shift));
    int best = -1;
    float best_d = tol;
    for (int j = 0; j < static_cast<int>(b.keypoints.size()); ++j) {
      if (b.keypoints[j].octave != ka.octave + octave_shift) continue;
      const float d = static_cast<float>(cv::norm(b.keypoints[j].pt - q));
      if (d <= best_d) {
        best_d = d;
        best = j;
      }
    }
    if (best >= 0) pairs.push_back({i, best});
  }
  return pairs;
}

// Share of pairs whose b is a's nearest neighbour by descriptor among all of b: what matching would find.
double nearestNeighbourShare(const OrbFeatures& a, const OrbFeatures& b, const std::vector<Pair>& pairs) {
  int hits = 0;
  for (const auto& p : pairs) {
    int best = -1, best_d = 257;
    for (int j = 0; j < static_cast<int>(b.descriptors.size()); ++j) {
      const int d = hamming(a.descriptors[p.a], b.descriptors[j]);
      if (d < best_d) {
        best_d = d;
        best = j;
      }
    }
    hits += best == p.b;
  }
  return pairs.empty() ? 0 : static_cast<double>(hits) / pairs.size();
}

}  // namespace

TEST(OrbSlamExtractor, KeepsTheBudgetOfEveryLevelOnARealFrame) {
  BINLOOP_REQUIRE_DATA(kittiLeft(0));
  const cv::Mat img = readGrayImage(kittiLeft(0));
  const OrbSlamExtractor ex;
  const std::vector<int> expected = {434, 362, 302, 251,
                                     209, 175, 145, 122};  // 2000 * (1 - 1/1.2) / (1 - 1.2^-8) ...
  ASSERT_EQ(ex.featuresPerLevel(), expected);
  const OrbFeatures f = ex.extract(img);
  ASSERT_EQ(f.keypoints.size(), f.descriptors.size());
  EXPECT_GE(f.keypoints.size(), 1960u);
  EXPECT_LE(f.keypoints.size(), 2024u);
  std::vector<int> per_level(8, 0);
  for (const auto& k : f.keypoints) {
    ASSERT_GE(k.octave, 0);
    ASSERT_LT(k.octave, 8);
    ++per_level[k.octave];
    const float scale = std::pow(1.2f, static_cast<float>(k.octave));
    EXPECT_NEAR(k.size, 31 * scale, 1e-3);
    EXPECT_GE(k.angle, 0.f);
    EXPECT_LT(k.angle, 360.f);
    EXPECT_GT(k.response, 0.f);
    // Level-0 coordinates, inside the border every level keeps.
    EXPECT_GE(k.pt.x, 19 * scale - 1);
    EXPECT_LE(k.pt.x, img.cols - 19 * scale + 1);
    EXPECT_GE(k.pt.y, 19 * scale - 1);
    EXPECT_LE(k.pt.y, img.rows - 19 * scale + 1);
  }
  for (int l = 0; l < 8; ++l) {
    EXPECT_GE(per_level[l], expected[l] * 95 / 100) << "level " << l;
    EXPECT_LE(per_level[l], expected[l] + 3) << "level " << l;
  }
  std::printf("keypoints %zu, per level:", f.keypoints.size());
  for (int n : per_level) std::printf(" %d", n);
  std::printf("\n");
}

TEST(OrbSlamExtractor, SpreadsKeypointsOverTheWholeRealFrame) {
  BINLOOP_REQUIRE_DATA(kittiLeft(0));
  const cv::Mat img = readGrayImage(kittiLeft(0));
  const double ours = gridCoverage(OrbSlamExtractor().extract(img).keypoints, img.size());
  std::vector<cv::KeyPoint> cv_kps;
  cv::ORB::create(2000, 1.2f, 8)->detect(img, cv_kps);
  const double opencv = gridCoverage(cv_kps, img.size());
  std::printf("16x6 cells covered: ours %.0f %%, OpenCV ORB %.0f %%\n", 100 * ours, 100 * opencv);
  EXPECT_GE(ours, 0.85);
  EXPECT_GT(ours, opencv + 0.2);
}

// Low-contrast texture (blobs 10 grey levels above the background) on the left half, strong texture (+-60)
// on the right: at ini_fast = 20 the left half has no corners, so only the min_fast fallback puts
// keypoints there.
TEST(OrbSlamExtractor, FallbackThresholdFindsCornersInLowContrastCells) {
  cv::Mat img(376, 752, CV_8UC1, cv::Scalar(128));
  HashRng rng(3);
  for (int i = 0; i < 3000; ++i) {
    const int x = rng.below(img.cols - 8), y = rng.below(img.rows - 8);
    const bool strong = x >= img.cols / 2 - 8, bright = rng.chance(0.5);
    cv::rectangle(img, {x, y}, {x + 2 + rng.below(6), y + 2 + rng.below(6)},
                  cv::Scalar(strong ? (bright ? 188 : 68) : 138), -1);
  }
  auto left_share = [&](const OrbSlamParams& p) {
    const OrbFeatures f = OrbSlamExtractor(p).extract(img);
    int left = 0;
    for (const auto& k : f.keypoints) left += k.pt.x < img.cols * 0.4;  // clear of the strong blobs' edge
    return f.keypoints.empty() ? 0.0 : static_cast<double>(left) / f.keypoints.size();
  };
  OrbSlamParams no_fallback;
  no_fallback.min_fast = no_fallback.ini_fast;
  const double with = left_share({}), without = left_share(no_fallback);
  std::printf("keypoints in the low-contrast 40 %%: %.0f %% with fallback, %.0f %% without\n", 100 * with,
              100 * without);
  EXPECT_GT(with, 0.25);
  EXPECT_LT(without, 0.02);
}

// The same physical corners in an image rotated about its centre must get the same descriptors and
// angles that differ by the rotation.
TEST(OrbSlamExtractor, DescriptorsAndAnglesFollowARotation) {
  BINLOOP_REQUIRE_DATA(kittiLeft(0));
  const cv::Mat full = readGrayImage(kittiLeft(0));
  const cv::Mat img = full(cv::Rect((full.cols - full.rows) / 2, 0, full.rows, full.rows)).clone();
  const cv::Point2f centre((img.cols - 1) / 2.f, (img.rows - 1) / 2.f);
  const OrbSlamExtractor ex;
  const OrbFeatures a = ex.extract(img);
  for (double deg : {30.0, 60.0, 90.0}) {
    const cv::Mat m = cv::getRotationMatrix2D(centre, deg, 1.0);
    cv::Mat rotated;
    cv::warpAffine(img, rotated, m, img.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0));
    const OrbFeatures b = ex.extract(rotated);
    const cv::Matx23d a_to_b(m);
    // The image content survives within the inscribed circle; stay clear of its rim.
    const auto pairs = samePoints(a, b, a_to_b, 0, centre, 0.4f * img.rows);
    ASSERT_GE(pairs.size(), 80u) << deg << " deg";
    // An angle rotates by atan2 of the rotated unit vector: -deg in image coordinates (y down).
    std::vector<double> hamming_of, angle_error;
    int close = 0, good_angle = 0;
    for (const auto& p : pairs) {
      const int h = hamming(a.descriptors[p.a], b.descriptors[p.b]);
      const double err = angleDiff(a.keypoints[p.a].angle - deg, b.keypoints[p.b].angle);
      hamming_of.push_back(h);
      angle_error.push_back(std::abs(err));
      close += h <= 50;
      good_angle += std::abs(err) <= 10;
    }
    const double n = static_cast<double>(pairs.size()), nn = nearestNeighbourShare(a, b, pairs);
    std::printf(
        "%2.0f deg: %zu same points, median Hamming %.0f, %.0f %% <= 50, median angle error %.1f deg, "
        "%.0f %% within 10 deg, %.0f %% nearest neighbours\n",
        deg, pairs.size(), median(hamming_of), 100 * close / n, median(angle_error), 100 * good_angle / n,
        100 * nn);
    EXPECT_GE(close / n, 0.7) << deg << " deg";
    EXPECT_LE(median(hamming_of), 35) << deg << " deg";
    EXPECT_LE(median(angle_error), 4) << deg << " deg";
    EXPECT_GE(good_angle / n, 0.8) << deg << " deg";
    EXPECT_GE(nn, 0.7) << deg << " deg";
  }
}

// An image shrunk by 1.2^2 shows each corner two octaves lower: same descriptor, same place.
TEST(OrbSlamExtractor, DescriptorsSurviveAScaleChangeOfTwoOctaves) {
  BINLOOP_REQUIRE_DATA(kittiLeft(0));
  const cv::Mat img = readGrayImage(kittiLeft(0));
  const double s = 1.2 * 1.2;
  cv::Mat small;
  cv::resize(img, small, cv::Size(cvRound(img.cols / s), cvRound(img.rows / s)), 0, 0, cv::INTER_AREA);
  const OrbSlamExtractor ex;
  const OrbFeatures big = ex.extract(img), sm = ex.extract(small);
  OrbFeatures low;  // the small image's keypoints that have an octave two above them in the big one
  for (size_t i = 0; i < sm.keypoints.size(); ++i)
    if (sm.keypoints[i].octave <= 5) {
      low.keypoints.push_back(sm.keypoints[i]);
      low.descriptors.push_back(sm.descriptors[i]);
    }
  const cv::Matx23d up(s, 0, 0, 0, s, 0);
  const auto pairs = samePoints(low, big, up, 2), same_octave = samePoints(low, big, up, 0);
  ASSERT_GE(pairs.size(), 150u);
  std::vector<double> h, h_same;
  int close = 0;
  for (const auto& p : pairs) {
    h.push_back(hamming(low.descriptors[p.a], big.descriptors[p.b]));
    close += h.back() <= 50;
  }
  // A corner also shows at neighbouring octaves, but seen at the wrong scale its descriptor differs.
  for (const auto& p : same_octave) h_same.push_back(hamming(low.descriptors[p.a], big.descriptors[p.b]));
  const double nn = nearestNeighbourShare(low, big, pairs);
  std::printf(
      "%zu keypoints at octave <= 5: %zu found two octaves up, median Hamming %.0f, %.0f %% <= 50, "
      "%.0f %% nearest neighbours; %zu at the same octave, median Hamming %.0f\n",
      low.keypoints.size(), pairs.size(), median(h), 100.0 * close / pairs.size(), 100 * nn,
      same_octave.size(), median(h_same));
  EXPECT_GE(static_cast<double>(pairs.size()) / low.keypoints.size(), 0.3);
  EXPECT_GT(median(h_same), 3 * median(h) + 10) << "the octave two up should hold the same descriptor";
  EXPECT_LE(median(h), 40);
  EXPECT_GE(static_cast<double>(close) / pairs.size(), 0.6);
  EXPECT_GE(nn, 0.6);
}

TEST(OrbSlamExtractor, SameImageSameFeatures) {
  BINLOOP_REQUIRE_DATA(kittiLeft(3));
  const cv::Mat img = readGrayImage(kittiLeft(3));
  const OrbFeatures a = OrbSlamExtractor().extract(img);
  const OrbSlamExtractor other;
  const OrbFeatures b = other.extract(other.pyramid(img.clone()));
  ASSERT_EQ(a.keypoints.size(), b.keypoints.size());
  for (size_t i = 0; i < a.keypoints.size(); ++i) {
    EXPECT_EQ(a.keypoints[i].pt, b.keypoints[i].pt);
    EXPECT_EQ(a.keypoints[i].octave, b.keypoints[i].octave);
    EXPECT_EQ(a.keypoints[i].angle, b.keypoints[i].angle);
    EXPECT_EQ(a.keypoints[i].response, b.keypoints[i].response);
    EXPECT_EQ(a.descriptors[i], b.descriptors[i]);
  }
}

TEST(OrbSlamExtractor, PyramidShrinksByTheScaleFactor) {
  const ImagePyramid p = buildPyramid(cv::Mat(376, 1241, CV_8UC1, cv::Scalar(9)), 8, 1.2f);
  ASSERT_EQ(p.levels.size(), 8u);
  EXPECT_EQ(p.levels[1].size(), cv::Size(1034, 313));
  EXPECT_EQ(p.levels[7].size(), cv::Size(346, 105));
  EXPECT_NEAR(p.scale[7], std::pow(1.2, 7), 1e-4);
}

TEST(OrbSlamExtractor, RefusesBadImagesParametersAndPyramids) {
  const OrbSlamExtractor ex;
  EXPECT_THROW_WITH(ex.extract(cv::Mat()), FeatureError, "empty image");
  EXPECT_THROW_WITH(ex.extract(cv::Mat(64, 64, CV_8UC3)), FeatureError,
                    "8-bit single-channel (grey) image, got CV_8UC3");
  EXPECT_THROW_WITH(ex.extract(cv::Mat(64, 64, CV_16UC1)), FeatureError, "got CV_16UC1");
  OrbSlamParams p;
  p.levels = 0;
  EXPECT_THROW_WITH(OrbSlamExtractor{p}, FeatureError, "levels must be >= 1, got 0");
  p = {};
  p.scale_factor = 1.f;
  EXPECT_THROW_WITH(OrbSlamExtractor{p}, FeatureError, "scale_factor must be > 1");
  p = {};
  p.min_fast = 30;
  EXPECT_THROW_WITH(OrbSlamExtractor{p}, FeatureError, "min_fast <= ini_fast, got 30 and 20");
  const cv::Mat img(100, 100, CV_8UC1, cv::Scalar(0));
  EXPECT_THROW_WITH(ex.extract(buildPyramid(img, 4, 1.2f)), FeatureError, "pyramid has 4 levels, expected 8");
  EXPECT_THROW_WITH(ex.extract(buildPyramid(img, 8, 1.5f)), FeatureError, "pyramid level 1 has scale 1.5");
}

TEST(OrbSlamExtractor, TinyAndFlatImagesGiveNoKeypoints) {
  const OrbSlamExtractor ex;
  EXPECT_TRUE(ex.extract(cv::Mat(20, 20, CV_8UC1, cv::Scalar(7))).keypoints.empty());
  EXPECT_TRUE(ex.extract(cv::Mat(376, 1241, CV_8UC1, cv::Scalar(7))).keypoints.empty());
}

// The learned pattern is ORB's: OpenCV's own ORB, building its own pyramid from the image, describes the
// extractor's keypoints with the same bits (its levels are resized slightly differently, so a few bits may
// differ above level 0).
TEST(OrbSlamExtractor, LearnedPatternGivesOpenCvOrbDescriptorsOfTheSameKeypoints) {
  BINLOOP_REQUIRE_DATA(kittiLeft(0));
  const cv::Mat img = readGrayImage(kittiLeft(0));
  OrbSlamParams learned;
  learned.pattern = BriefPatternKind::kOrbLearned;
  const OrbSlamExtractor ex(learned);
  const OrbFeatures f = ex.extract(img);
  std::vector<cv::KeyPoint> kps = f.keypoints;
  cv::Mat theirs;
  cv::ORB::create(2000, 1.2f, 8, 0)->compute(img, kps, theirs);
  ASSERT_EQ(static_cast<size_t>(theirs.rows), f.descriptors.size());
  int level0 = 0, level0_same = 0, close = 0;
  for (int i = 0; i < theirs.rows; ++i) {
    Desc256 d;
    std::memcpy(d.w.data(), theirs.ptr<uint8_t>(i), 32);
    const int h = hamming(d, f.descriptors[i]);
    close += h <= 10;
    if (f.keypoints[i].octave == 0) {
      ++level0;
      level0_same += h == 0;
    }
  }
  EXPECT_GT(level0, 300);
  EXPECT_EQ(level0_same, level0);
  EXPECT_GE(close, theirs.rows * 95 / 100);
}

// What the learned pattern is for: on a real frame its bits are far less biased than the Gaussian ones
// (ORB paper, section 4), and two unrelated descriptors differ in about half of them.
TEST(OrbSlamExtractor, LearnedPatternBitsAreBalancedOnARealFrame) {
  BINLOOP_REQUIRE_DATA(kittiLeft(0));
  const cv::Mat img = readGrayImage(kittiLeft(0));
  OrbSlamParams orb;
  orb.pattern = BriefPatternKind::kOrbLearned;
  const BitStatistics learned = bitStatistics(OrbSlamExtractor(orb).extract(img).descriptors);
  const BitStatistics old = bitStatistics(OrbSlamExtractor().extract(img).descriptors);
  std::printf("mean |P(1) - 0.5|: learned %.3f, Gaussian %.3f; random pairs %.1f vs %.1f bits apart\n",
              learned.mean_bias, old.mean_bias, learned.random_pair_distance, old.random_pair_distance);
  EXPECT_LT(learned.mean_bias, 0.10);
  EXPECT_GT(old.mean_bias, 0.15);
  EXPECT_GT(learned.random_pair_distance, 118);
  EXPECT_LT(old.random_pair_distance, 110);
}

TEST(OrbSlamExtractor, ModelHeaderRecordsThePattern) {
  OrbSlamParams learned;
  learned.pattern = BriefPatternKind::kOrbLearned;
  EXPECT_EQ(OrbSlamParams{}.pattern, BriefPatternKind::kGaussian) << "the SLAM's default";
  const ExtractorSettings a = extractorSettings(learned), b = extractorSettings(OrbSlamParams{});
  EXPECT_NE(a, b);
  EXPECT_NE(a.differences(b).find("learned"), std::string::npos) << a.differences(b);
  EXPECT_EQ(briefPatternFromName("gaussian"), BriefPatternKind::kGaussian);
  EXPECT_THROW(briefPatternFromName("brisk"), FeatureError);
}
