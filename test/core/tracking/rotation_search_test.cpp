// The rotation after lost frames (include/binloop/tracking/rotation_search.h) on hand-made scenes: far
// points seen from a camera turned by several degrees from the prediction, with keypoints that are wrong
// or belong to nothing, and a position that is also a little off.
#include "binloop/tracking/rotation_search.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace binloop {
namespace {

constexpr double kDeg = M_PI / 180.0;

// KITTI 00-02's rectified stereo pair (1241x376, fx 718.9, baseline 0.54 m).
StereoCamera camera() { return kitti00Camera(); }

Eigen::Matrix3d turn(double yaw_deg, double pitch_deg, double roll_deg) {
  return (Eigen::AngleAxisd(yaw_deg * kDeg, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(pitch_deg * kDeg, Eigen::Vector3d::UnitX()) *
          Eigen::AngleAxisd(roll_deg * kDeg, Eigen::Vector3d::UnitZ()))
      .toRotationMatrix();
}

Desc256 randomDesc(std::mt19937_64& g) {
  Desc256 d;
  for (auto& w : d.w) w = g();
  return d;
}

struct Scene {
  std::vector<msg::MapPoint> points;
  Frame frame;
  Pose3 truth = Pose3::Identity();
};

// `n` points 30-90 m ahead; the true camera is the prediction (identity) turned and moved by `offset_m`;
// a share `wrong` of the points is seen at a random place, and `clutter` keypoints belong to nothing.
Scene makeScene(const Eigen::Matrix3d& R, double offset_m, int n, double wrong, int clutter, uint64_t seed) {
  std::mt19937_64 g(seed);
  std::uniform_real_distribution<double> U(0, 1);
  const StereoCamera cam = camera();
  const ScalePyramid s(1.2f, 8);
  Scene sc;
  sc.truth.linear() = R;
  sc.truth.translation() = Eigen::Vector3d(0.3, -0.1, 1.0).normalized() * offset_m;
  std::vector<msg::KeyPoint> kps;
  for (int i = 0; i < n; ++i) {
    msg::MapPoint mp;
    mp.id = static_cast<MapPointId>(i + 1);
    const double z = 30 + 60 * U(g);
    mp.p_w = {(U(g) - 0.5) * 1.6 * z, (U(g) - 0.5) * 0.5 * z, z};
    mp.descriptor = randomDesc(g);
    mp.max_distance = static_cast<float>(z * 1.5);
    mp.min_distance = mp.max_distance / s.scale.back();
    mp.normal = mp.p_w.normalized().cast<float>();
    sc.points.push_back(mp);
    const Eigen::Vector3d c = sc.truth.inverse() * mp.p_w;
    msg::KeyPoint k;
    if (U(g) < wrong) {
      k.x = static_cast<float>(U(g) * cam.width);
      k.y = static_cast<float>(U(g) * cam.height);
    } else {
      k.x = static_cast<float>(cam.fx * c.x() / c.z() + cam.cx);
      k.y = static_cast<float>(cam.fy * c.y() / c.z() + cam.cy);
    }
    if (k.x < 0 || k.y < 0 || k.x >= cam.width || k.y >= cam.height) continue;
    k.octave = static_cast<uint8_t>(s.predictLevel(mp.max_distance, static_cast<float>(c.norm())));
    kps.push_back(k);
    sc.frame.descriptors.push_back(mp.descriptor);
  }
  for (int i = 0; i < clutter; ++i) {
    msg::KeyPoint k;
    k.x = static_cast<float>(U(g) * cam.width);
    k.y = static_cast<float>(U(g) * cam.height);
    k.octave = static_cast<uint8_t>(g() % 4);
    kps.push_back(k);
    sc.frame.descriptors.push_back(randomDesc(g));
  }
  sc.frame.keypoints = kps;
  sc.frame.grid = KeypointGrid(kps, cam.width, cam.height);
  sc.frame.points.assign(kps.size(), kNoId);
  sc.frame.outlier.assign(kps.size(), 0);
  return sc;
}

std::vector<const msg::MapPoint*> pointers(const Scene& sc) {
  std::vector<const msg::MapPoint*> out;
  for (const auto& p : sc.points) out.push_back(&p);
  return out;
}

double angleDeg(const Eigen::Matrix3d& A, const Eigen::Matrix3d& B) {
  return Eigen::AngleAxisd(A.transpose() * B).angle() / kDeg;
}

TEST(RotationBetweenBearings, RecoversARotationFromTwoBearings) {
  const Eigen::Matrix3d R = turn(5, -2, 1);
  const Eigen::Vector3d a = Eigen::Vector3d(0.2, 0.1, 1).normalized(),
                        b = Eigen::Vector3d(-0.4, 0, 1).normalized();
  EXPECT_LT(angleDeg(rotationBetweenBearings({R * a, R * b}, {a, b}), R), 1e-9);
  EXPECT_TRUE(rotationBetweenBearings({R * a}, {a}).isIdentity());
}

TEST(RotationSearch, FindsTheRotationAmongWrongMatchesAndClutter) {
  const ScalePyramid s(1.2f, 8);
  const Eigen::Matrix3d R = turn(5, 1, 0.3);
  // 40 % of the points at random places, 600 keypoints of nothing, the position 0.5 m off.
  const Scene sc = makeScene(R, 0.5, 150, 0.4, 600, 3);
  const RotationSearchResult r =
      searchRotation(sc.frame, Pose3::Identity(), pointers(sc), camera(), s, {}, 7);
  ASSERT_TRUE(r.ok) << r.inliers << " of " << r.candidates;
  EXPECT_LT(angleDeg(r.R_pred_c, R), 0.15)
      << "the prediction was " << angleDeg(Eigen::Matrix3d::Identity(), R);
  EXPECT_GE(r.inliers, 60);
  // Same seed, same answer.
  const RotationSearchResult again =
      searchRotation(sc.frame, Pose3::Identity(), pointers(sc), camera(), s, {}, 7);
  EXPECT_EQ(again.inliers, r.inliers);
  EXPECT_TRUE(again.R_pred_c == r.R_pred_c);
}

TEST(RotationSearch, NearPointsDoNotTakePart) {
  const ScalePyramid s(1.2f, 8);
  const Scene sc = makeScene(turn(3, 0, 0), 0.2, 150, 0, 0, 4);
  RotationSearchParams p;
  p.min_distance_m = 200;  // every point is nearer
  const RotationSearchResult r = searchRotation(sc.frame, Pose3::Identity(), pointers(sc), camera(), s, p, 7);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.candidates, 0);
}

TEST(RotationSearch, ATurnBeyondTheWindowIsNotFound) {
  const ScalePyramid s(1.2f, 8);
  // 15 degrees of yaw; the window allows 8: what is found must not be passed off as the rotation.
  const Scene sc = makeScene(turn(15, 0, 0), 0.0, 150, 0, 0, 5);
  const RotationSearchResult r =
      searchRotation(sc.frame, Pose3::Identity(), pointers(sc), camera(), s, {}, 7);
  EXPECT_FALSE(r.ok) << r.inliers << " inliers";
}

}  // namespace
}  // namespace binloop
