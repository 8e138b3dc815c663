#include "binloop/features/stereo_matcher.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "binloop/features/feature_error.h"
#include "binloop/io/kitti_calib.h"
#include "binloop/io/kitti_sequence.h"
#include "binloop/util/hash_random.h"
#include "support/test_support.h"

using namespace binloop;

namespace {

std::string kitti(const char* side, int i) {
  char name[32];
  std::snprintf(name, sizeof name, "%06d.png", i);
  return test::sharedData("kitti/sample_00/") + side + "/" + name;
}

struct Side {
  ImagePyramid pyramid;
  OrbFeatures features;
};

Side extract(const cv::Mat& img) {
  static const OrbSlamExtractor ex;
  Side s{ex.pyramid(img), {}};
  s.features = ex.extract(s.pyramid);
  return s;
}

// The right image of a fronto-parallel scene at disparity d (x_right = x_left - d), shifted by dy rows too
// when asked; bilinear, so a fractional d is a true sub-pixel shift.
cv::Mat shifted(const cv::Mat& left, double d, double dy = 0) {
  const cv::Matx23d m(1, 0, -d, 0, 1, dy);
  cv::Mat right;
  cv::warpAffine(left, right, m, left.size(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  return right;
}

struct ShiftResult {
  double match_rate = 0;  // share of left keypoints with a depth
  double accurate = 0;    // share of matches within 0.2 px of d
  double near_d = 0;      // share of matches within 1 px of d
  float max_disparity = 0;
  int matched = 0, rejected_by_sad = 0;
};

ShiftResult matchShift(const cv::Mat& left_img, double d, const StereoMatchParams& p = {}, double dy = 0) {
  const StereoCamera cam = kitti00Camera();
  const Side l = extract(left_img), r = extract(shifted(left_img, d, dy));
  const StereoMatches m = matchStereo(l.features, l.pyramid, r.features, r.pyramid, cam, p);
  ShiftResult res;
  int accurate = 0, near_d = 0;
  for (size_t i = 0; i < l.features.keypoints.size(); ++i) {
    if (m.depth[i] < 0) {
      EXPECT_EQ(m.right_x[i], -1.f);
      continue;
    }
    ++res.matched;
    const float disparity = l.features.keypoints[i].pt.x - m.right_x[i];
    EXPECT_NEAR(m.depth[i], cam.bf() / disparity, 1e-4 * m.depth[i]);
    accurate += std::abs(disparity - d) < 0.2;
    near_d += std::abs(disparity - d) < 1;
    res.max_disparity = std::max(res.max_disparity, disparity);
  }
  EXPECT_EQ(res.matched, m.matched);
  res.rejected_by_sad = m.rejected_by_sad;
  res.match_rate = static_cast<double>(res.matched) / l.features.keypoints.size();
  res.accurate = res.matched ? static_cast<double>(accurate) / res.matched : 0;
  res.near_d = res.matched ? static_cast<double>(near_d) / res.matched : 0;
  return res;
}

}  // namespace

// A real image shifted by a known disparity: matched points must come back at that disparity, and the
// sub-pixel step must recover fractional shifts, not only whole pixels. ORB-SLAM2's centre-pixel offset
// is printed for comparison (see stereo_matcher.h).
TEST(StereoMatcher, RecoversAKnownDisparityToASubPixel) {
  BINLOOP_REQUIRE_DATA(kitti("image_0", 0));
  const cv::Mat left = readGrayImage(kitti("image_0", 0));
  StereoMatchParams equiangular, orbslam2;
  equiangular.fit = StereoMatchParams::SubPixelFit::kEquiangular;
  orbslam2.centre_pixel_offset = true;
  for (double d : {12.0, 7.5, 20.25, 33.7}) {
    const ShiftResult r = matchShift(left, d), e = matchShift(left, d, equiangular),
                      o = matchShift(left, d, orbslam2);
    std::printf(
        "disparity %5.2f: %.0f %% of keypoints matched (%d more dropped by SAD); within 0.2 px: %.0f %% "
        "(parabola), %.0f %% (equiangular), %.0f %% (ORB-SLAM2's centre offset); within 1 px: %.0f %%\n",
        d, 100 * r.match_rate, r.rejected_by_sad, 100 * r.accurate, 100 * e.accurate, 100 * o.accurate,
        100 * r.near_d);
    EXPECT_GE(r.match_rate, 0.45) << "d = " << d;
    EXPECT_GE(r.accurate, 0.7) << "d = " << d;
    EXPECT_GE(r.near_d, 0.97) << "d = " << d;
    EXPECT_GE(e.accurate, 0.9) << "d = " << d;
  }
}

// With the right image 10 rows off, the true partner is outside the row band of every octave (+-2 rows
// times 1.2^octave, at most 7.2): what still matches is wrong, never at the true disparity.
TEST(StereoMatcher, SearchesOnlyNearTheKeypointsRow) {
  BINLOOP_REQUIRE_DATA(kitti("image_0", 0));
  const cv::Mat left = readGrayImage(kitti("image_0", 0));
  const ShiftResult aligned = matchShift(left, 10), off = matchShift(left, 10, {}, 10);
  const double right_aligned = aligned.match_rate * aligned.near_d, right_off = off.match_rate * off.near_d;
  std::printf(
      "keypoints matched at the true disparity: %.1f %% on the row, %.1f %% with the right image 10 rows "
      "off\n",
      100 * right_aligned, 100 * right_off);
  EXPECT_GE(right_aligned, 0.5);
  EXPECT_LT(right_off, 0.02);
}

TEST(StereoMatcher, SearchesOnlyTheDisparityRangeOfTheMinimumDepth) {
  BINLOOP_REQUIRE_DATA(kitti("image_0", 0));
  const cv::Mat left = readGrayImage(kitti("image_0", 0));
  StereoMatchParams near_limit;
  near_limit.min_depth_m = kitti00Camera().bf() / 20;  // disparities below 20 px
  const ShiftResult inside = matchShift(left, 18, near_limit), beyond = matchShift(left, 24, near_limit);
  std::printf("with disparities limited to 20 px: %.0f %% matched at 18 px, %.1f %% at 24 px\n",
              100 * inside.match_rate, 100 * beyond.match_rate);
  EXPECT_GE(inside.match_rate, 0.4);
  EXPECT_GE(inside.near_d, 0.97);
  EXPECT_LT(inside.max_disparity, 20.f);
  EXPECT_LT(beyond.max_disparity, 20.f);
  EXPECT_LT(beyond.match_rate, 0.05);
}

// Noise on a band of the right image leaves descriptors (on the blurred image) matching but makes SAD
// large there: those matches are the outliers the median test must drop, and only those. Counted at
// octave 0 only, as the pyramid averages the noise away at coarser levels.
TEST(StereoMatcher, DropsMatchesWhoseSadIsFarAboveTheMedian) {
  BINLOOP_REQUIRE_DATA(kitti("image_0", 0));
  const cv::Mat left = readGrayImage(kitti("image_0", 0));
  // Sensor-like noise (sigma 2) everywhere, heavy noise (sigma 30) on the left quarter.
  const cv::Rect band(0, 0, left.cols / 4, left.rows);
  cv::Mat right(left.size(), CV_8UC1);
  const cv::Mat clean_right = shifted(left, 10);
  HashRng rng(11);
  for (int y = 0; y < right.rows; ++y)
    for (int x = 0; x < right.cols; ++x) {
      const double sigma = band.contains({x, y}) ? 30 : 2;
      right.at<uint8_t>(y, x) =
          cv::saturate_cast<uint8_t>(clean_right.at<uint8_t>(y, x) + sigma * rng.normal());
    }
  const Side l = extract(left), r = extract(right);
  StereoMatchParams keep_all;
  keep_all.sad_outlier_factor = 1e9f;
  const StereoCamera cam = kitti00Camera();
  const StereoMatches m = matchStereo(l.features, l.pyramid, r.features, r.pyramid, cam);
  const StereoMatches all = matchStereo(l.features, l.pyramid, r.features, r.pyramid, cam, keep_all);
  // Outside the band, count right (at the true disparity) and wrong matches separately: the test should
  // keep the right ones and may drop wrong ones, whose SAD is high for the same reason.
  int in_band_all = 0, in_band = 0, right_all = 0, right_kept = 0, wrong_all = 0, wrong_kept = 0;
  for (size_t i = 0; i < l.features.keypoints.size(); ++i) {
    const auto& k = l.features.keypoints[i];
    if (k.octave != 0 || all.depth[i] < 0) continue;
    const bool kept = m.depth[i] > 0;
    if (k.pt.x < band.width + 20) {
      ++in_band_all;
      in_band += kept;
    } else if (std::abs(k.pt.x - all.right_x[i] - 10) < 1) {
      ++right_all;
      right_kept += kept;
    } else {
      ++wrong_all;
      wrong_kept += kept;
    }
  }
  std::printf(
      "octave-0 matches kept: noisy band %d of %d; elsewhere right %d of %d, wrong %d of %d (SAD "
      "threshold %.0f)\n",
      in_band, in_band_all, right_kept, right_all, wrong_kept, wrong_all, m.sad_threshold);
  EXPECT_EQ(all.rejected_by_sad, 0);
  EXPECT_EQ(m.matched + m.rejected_by_sad, all.matched);
  ASSERT_GE(in_band_all, 30);
  ASSERT_GE(right_all, 100);
  EXPECT_LT(in_band, in_band_all / 4);
  EXPECT_GE(right_kept, right_all * 95 / 100);
  EXPECT_LT(wrong_kept, wrong_all / 2 + 1);
}

// The real pair: a share of the keypoints gets a depth, every depth is positive and finite, nearly all
// lie within 80 m, and the road in the bottom rows is where a camera 1.65 m above it puts it (rows 300-376:
// 10.3-6.2 m).
TEST(StereoMatcher, GivesPlausibleDepthsOnTheRealKittiPairs) {
  BINLOOP_REQUIRE_DATA(test::sharedData("kitti/sample_00/calib.txt"));
  StereoCamera cam = readKittiCalib(test::sharedData("kitti/sample_00/calib.txt"));
  double rate = 0;
  for (int f = 0; f <= 10; ++f) {
    const Side l = extract(readGrayImage(kitti("image_0", f))),
               r = extract(readGrayImage(kitti("image_1", f)));
    const StereoMatches m = matchStereo(l.features, l.pyramid, r.features, r.pyramid, cam);
    int far = 0, close = 0;
    std::vector<float> road;
    for (size_t i = 0; i < m.depth.size(); ++i) {
      if (m.depth[i] < 0) continue;
      const auto& k = l.features.keypoints[i];
      ASSERT_TRUE(std::isfinite(m.depth[i]));
      ASSERT_GT(m.depth[i], 0);
      ASSERT_LE(m.right_x[i], k.pt.x);
      ASSERT_GE(m.right_x[i], 0);
      far += m.depth[i] > 80;
      close += isCloseDepth(m.depth[i], cam);
      if (k.pt.y > 300 && std::abs(k.pt.x - cam.cx) < 300) road.push_back(m.depth[i]);
    }
    std::sort(road.begin(), road.end());
    const double share = static_cast<double>(m.matched) / l.features.keypoints.size();
    rate += share / 11;
    std::printf(
        "frame %2d: %4d of %4zu matched (%.0f %%), %d beyond 80 m, %d close, %d dropped by SAD, road "
        "median %.1f m\n",
        f, m.matched, l.features.keypoints.size(), 100 * share, far, close, m.rejected_by_sad,
        road.empty() ? 0.f : road[road.size() / 2]);
    EXPECT_GE(share, 0.4) << "frame " << f;
    EXPECT_LT(far, m.matched / 10) << "frame " << f;
    EXPECT_GT(close, m.matched / 2) << "frame " << f;
    ASSERT_GE(road.size(), 10u) << "frame " << f;
    EXPECT_GT(road[road.size() / 2], 5.f) << "frame " << f;
    EXPECT_LT(road[road.size() / 2], 11.f) << "frame " << f;
  }
  std::printf("mean match rate over 11 real pairs: %.1f %%\n", 100 * rate);
}

TEST(StereoMatcher, CloseMeansUnderFortyBaselines) {
  const StereoCamera cam = kitti00Camera();  // 40 * 0.537 = 21.48 m
  EXPECT_TRUE(isCloseDepth(21.4f, cam));
  EXPECT_FALSE(isCloseDepth(21.5f, cam));
  EXPECT_FALSE(isCloseDepth(-1.f, cam));
  EXPECT_FALSE(isCloseDepth(0.f, cam));
  StereoMatchParams p;
  p.close_depth_baselines = 35;  // ORB-SLAM2's KITTI setting
  EXPECT_FALSE(isCloseDepth(19.f, cam, p));
}

TEST(StereoMatcher, RefusesInconsistentInput) {
  const cv::Mat img(100, 200, CV_8UC1, cv::Scalar(50));
  const Side s = extract(img);
  const StereoCamera cam = kitti00Camera();
  OrbFeatures f;
  f.keypoints.emplace_back(cv::Point2f(50, 50), 31.f, 0.f, 1.f, 0);
  EXPECT_THROW_WITH(matchStereo(f, s.pyramid, s.features, s.pyramid, cam), FeatureError,
                    "left side has 1 keypoints but 0 descriptors");
  f.descriptors.emplace_back();
  f.keypoints[0].octave = 9;
  EXPECT_THROW_WITH(matchStereo(s.features, s.pyramid, f, s.pyramid, cam), FeatureError,
                    "right keypoint of octave 9 but the pyramid has 8 levels");
  StereoCamera mono = cam;
  mono.baseline_m = 0;
  EXPECT_THROW_WITH(matchStereo(s.features, s.pyramid, s.features, s.pyramid, mono), FeatureError,
                    "positive baseline");
  StereoMatchParams no_slide;
  no_slide.sad_search_px = 0;
  EXPECT_THROW_WITH(matchStereo(s.features, s.pyramid, s.features, s.pyramid, cam, no_slide), FeatureError,
                    "parameters out of range");
  const Side other = extract(cv::Mat(100, 190, CV_8UC1, cv::Scalar(50)));
  EXPECT_THROW_WITH(matchStereo(s.features, s.pyramid, other.features, other.pyramid, cam), FeatureError,
                    "pyramid level 0 differs between left and right");
}
