// What a keypoint measures for the estimators (include/binloop/map/keypoint_geometry.h): a far keypoint's
// disparity is left out unless asked for, a close one's always kept; its depth is untouched either way.
#include "binloop/map/keypoint_geometry.h"

#include <gtest/gtest.h>

namespace binloop {
namespace {

msg::KeyPoint at(float depth_m, const StereoCamera& c) {
  msg::KeyPoint k{600.f, 180.f, 0.f, 0, -1.f, depth_m};
  if (depth_m > 0) k.right_x = k.x - static_cast<float>(c.bf() / depth_m);
  return k;
}

StereoMatchParams stereo(double close_depth_baselines, bool far_disparity) {
  StereoMatchParams p;
  p.close_depth_baselines = close_depth_baselines;
  p.far_disparity = far_disparity;
  return p;
}

TEST(KeypointGeometry, AFarKeypointsDisparityIsMeasuredOnlyWhenAskedFor) {
  const StereoCamera c = kitti00Camera();  // 40 baselines: 21.49 m
  const msg::KeyPoint close = at(21.4f, c), far = at(21.6f, c), none = at(-1.f, c);
  EXPECT_EQ(measuredRightX(close, c, stereo(40, false)), close.right_x);
  EXPECT_EQ(measuredRightX(close, c, stereo(40, true)), close.right_x);
  EXPECT_EQ(measuredRightX(far, c, stereo(40, false)), -1.f);
  EXPECT_EQ(measuredRightX(far, c, stereo(40, true)), far.right_x);
  EXPECT_EQ(measuredRightX(far, c, stereo(50, false)), far.right_x);  // close by a wider bound
  EXPECT_EQ(measuredRightX(none, c, stereo(40, true)), -1.f);
  EXPECT_EQ(measuredRightX(none, c, stereo(40, false)), -1.f);
  EXPECT_NEAR(unprojectKeypoint(far, c).z(), 21.6, 1e-5);  // the depth still places a point
}

}  // namespace
}  // namespace binloop
