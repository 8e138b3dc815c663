#include "binloop/eval/disparity_error.h"

#include <gtest/gtest.h>

#include <limits>

#include "support/test_support.h"

using namespace binloop;

namespace {

StereoCamera smallCamera() {
  StereoCamera cam;
  cam.fx = cam.fy = 100;
  cam.cx = 20;
  cam.cy = 15;
  cam.width = 40;
  cam.height = 30;
  cam.baseline_m = 0.5;
  return cam;
}

msg::KeyPoint at(float x, float y, float depth) {
  msg::KeyPoint k;
  k.x = x;
  k.y = y;
  k.depth = depth;
  return k;
}

}  // namespace

// A wall 10 m away (true disparity 5 px): a keypoint measured at 12.5 m is 1 px short, one measured at 10 m
// is right; a keypoint without a stereo match and one where the wall ends (an occluding edge) give nothing.
TEST(DisparityError, MeasuresAgainstTheTrueDepthAwayFromEdges) {
  const StereoCamera cam = smallCamera();
  cv::Mat depth(cam.height, cam.width, CV_32F, cv::Scalar(10.f));
  depth.colRange(30, 40).setTo(std::numeric_limits<float>::infinity());  // sky beside the wall
  const auto e =
      disparityErrors({at(10.5f, 10, 12.5f), at(15, 12.25f, 10), at(15, 12, -1), at(29, 10, 10)}, depth, cam);
  ASSERT_EQ(e.size(), 2u);
  EXPECT_NEAR(e[0].true_disparity, 5, 1e-5);
  EXPECT_NEAR(e[0].error, -1, 1e-5);
  EXPECT_NEAR(e[1].error, 0, 1e-5);
  EXPECT_NEAR(e[1].true_disparity, 5, 1e-5);
}

TEST(DisparityError, SummariesGiveBiasNoiseAndWrongMatchesPerRange) {
  std::vector<DisparityError> e;
  for (float err : {0.1f, 0.2f, 0.3f, 0.2f, 3.0f}) e.push_back({6, err});
  e.push_back({20, -0.5f});
  const auto s = summariseDisparityErrors(e, {0, 4, 8, 32});
  ASSERT_EQ(s.size(), 3u);
  EXPECT_EQ(s[0].n, 0u);
  EXPECT_EQ(s[1].n, 5u);
  EXPECT_NEAR(s[1].median, 0.2, 1e-6);
  EXPECT_NEAR(s[1].mad, 0.1, 1e-6);
  EXPECT_NEAR(s[1].wrong, 0.2, 1e-9);
  EXPECT_EQ(s[2].n, 1u);
  EXPECT_NEAR(s[2].median, -0.5, 1e-6);
}

TEST(DisparityError, RefusesADepthImageOfAnotherSizeOrType) {
  const StereoCamera cam = smallCamera();
  EXPECT_THROW_WITH(disparityErrors({}, cv::Mat(cam.height, cam.width + 1, CV_32F), cam),
                    std::invalid_argument, "camera's size");
  EXPECT_THROW_WITH(disparityErrors({}, cv::Mat(cam.height, cam.width, CV_64F), cam), std::invalid_argument,
                    "CV_32F");
}
