#include "binloop/mapping/epipolar_matcher.h"

#include <gtest/gtest.h>

#include "../optim/optim_test_scene.h"
#include "support/random_descriptors.h"

namespace binloop {
namespace {

using test::flipBits;
using test::randomDescriptor;

struct View {
  Pose3 T_w_c;
  std::vector<msg::KeyPoint> kps;
  Descriptors desc;
  std::vector<MapPointId> ids;
  std::vector<int> truth;  // index of the scene point, -1 for a distractor
  EpipolarView view(const StereoCamera& cam) const { return {&T_w_c, &cam, &kps, &desc, &ids}; }
};

bool project(const StereoCamera& cam, const Pose3& T_w_c, const Eigen::Vector3d& X, msg::KeyPoint* k) {
  const Eigen::Vector3d p = T_w_c.inverse() * X;
  if (p.z() < 1) return false;
  k->x = static_cast<float>(cam.fx * p.x() / p.z() + cam.cx);
  k->y = static_cast<float>(cam.fy * p.y() / p.z() + cam.cy);
  return k->x >= 0 && k->x < cam.width && k->y >= 0 && k->y < cam.height;
}

// Two keyframes 2 m apart along the optical axis with a 3-degree yaw, seeing 300 points.
class EpipolarMatcherTest : public ::testing::Test {
 protected:
  void SetUp() override {
    HashRng rng(7);
    a.T_w_c = Pose3::Identity();
    b.T_w_c = Pose3::Identity();
    b.T_w_c.linear() = Eigen::AngleAxisd(3 * test::kPi / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
    b.T_w_c.translation() = Eigen::Vector3d(0.2, 0, 2.0);
    for (int n = 0; n < 300; ++n) {
      const Eigen::Vector3d X(rng.uniform(-15, 15), rng.uniform(-3, 2), rng.uniform(8, 60));
      msg::KeyPoint ka, kb;
      if (!project(cam, a.T_w_c, X, &ka) || !project(cam, b.T_w_c, X, &kb)) continue;
      const Desc256 d = randomDescriptor(rng);
      ka.angle = static_cast<float>(rng.uniform(0, 360));
      kb.angle = ka.angle + 2;
      for (View* v : {&a, &b}) {
        v->kps.push_back(v == &a ? ka : kb);
        v->desc.push_back(flipBits(d, 8, rng));
        v->ids.push_back(kNoId);
        v->truth.push_back(static_cast<int>(points.size()));
      }
      points.push_back(X);
    }
  }
  StereoCamera cam = test::kitti();
  View a, b;
  std::vector<Eigen::Vector3d> points;
  ScalePyramid scales{1.2f, 8};
};

TEST_F(EpipolarMatcherTest, FundamentalMatrixMapsPointsOntoTheirEpipolarLines) {
  const Eigen::Matrix3d F = fundamentalMatrix(a.T_w_c, b.T_w_c, cam);
  for (size_t i = 0; i < a.kps.size(); ++i) {
    const Eigen::Vector3d l = F * Eigen::Vector3d(a.kps[i].x, a.kps[i].y, 1);
    const double d = (l.x() * b.kps[i].x + l.y() * b.kps[i].y + l.z()) / std::hypot(l.x(), l.y());
    EXPECT_LT(std::abs(d), 0.01) << "point " << i;
  }
}

TEST_F(EpipolarMatcherTest, MatchesTheTrueCorrespondences) {
  ASSERT_GT(a.kps.size(), 150u);
  const auto m = matchAlongEpipolarLines(a.view(cam), b.view(cam), scales);
  int right = 0;
  for (const auto& [i, j] : m) right += a.truth[i] == b.truth[j];
  EXPECT_EQ(right, static_cast<int>(m.size()));
  EXPECT_GT(right, 0.95 * a.kps.size());
}

TEST_F(EpipolarMatcherTest, AnIdenticalDescriptorOffTheEpipolarLineIsNotMatched) {
  // Each of b's keypoints gets a twin 20 px across its epipolar line with a closer descriptor than the
  // true one.
  const Eigen::Matrix3d F = fundamentalMatrix(a.T_w_c, b.T_w_c, cam);
  const size_t n = b.kps.size();
  for (size_t j = 0; j < n; ++j) {
    const Eigen::Vector3d l = F * Eigen::Vector3d(a.kps[j].x, a.kps[j].y, 1);
    const Eigen::Vector2d across = l.head<2>().normalized();
    msg::KeyPoint k = b.kps[j];
    k.x += static_cast<float>(20 * across.x());
    k.y += static_cast<float>(20 * across.y());
    b.kps.push_back(k);
    b.desc.push_back(a.desc[j]);
    b.ids.push_back(kNoId);
    b.truth.push_back(-1);
  }
  const auto m = matchAlongEpipolarLines(a.view(cam), b.view(cam), scales);
  for (const auto& [i, j] : m) EXPECT_EQ(a.truth[i], b.truth[j]) << "keypoint " << i << " matched " << j;
  EXPECT_GT(m.size(), 0.95 * n);
}

TEST_F(EpipolarMatcherTest, KeypointsWithAMapPointAreLeftAlone) {
  for (size_t i = 0; i < a.ids.size(); i += 2) a.ids[i] = 42;
  for (const auto& [i, j] : matchAlongEpipolarLines(a.view(cam), b.view(cam), scales))
    EXPECT_EQ(a.ids[i], kNoId);
}

TEST_F(EpipolarMatcherTest, MatchesWithAnInconsistentRotationAreDropped) {
  // A few (5 %) turned 90 degrees: a bin that small next to the true rotation's is dropped.
  for (size_t j = 0; j < b.kps.size(); j += 20) b.kps[j].angle += 90;
  const auto m = matchAlongEpipolarLines(a.view(cam), b.view(cam), scales);
  EXPECT_GT(m.size(), 0.9 * b.kps.size());
  for (const auto& [i, j] : m) EXPECT_NE(j % 20, 0) << "keypoint " << j << " turned 90 degrees was kept";
}

}  // namespace
}  // namespace binloop
