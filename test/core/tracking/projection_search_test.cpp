// Projection search on hand-made frames (include/binloop/tracking/projection_search.h): every point of a
// known scene must find its own keypoint from a slightly wrong pose, and nothing else may be matched.
#include "binloop/tracking/projection_search.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>
#include <unordered_map>

namespace binloop {
namespace {

constexpr double kDeg = M_PI / 180.0;

StereoCamera camera() {
  StereoCamera c;
  c.fx = c.fy = 500;
  c.cx = 320;
  c.cy = 240;
  c.baseline_m = 0.5;
  c.width = 640;
  c.height = 480;
  return c;
}

Pose3 pose(double rx_deg, double ry_deg, double rz_deg, const Eigen::Vector3d& t) {
  Pose3 T = Pose3::Identity();
  T.linear() = (Eigen::AngleAxisd(rz_deg * kDeg, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(ry_deg * kDeg, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(rx_deg * kDeg, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = t;
  return T;
}

Desc256 randomDesc(std::mt19937_64& g) {
  Desc256 d;
  for (auto& w : d.w) w = g();
  return d;
}

Desc256 flipBits(Desc256 d, int n, int first = 0) {
  for (int b = 0; b < n; ++b) d.w[((first + b * 37) % 256) >> 6] ^= uint64_t{1} << ((first + b * 37) % 64);
  return d;
}

/// A point straight ahead of an identity camera at depth z, seen head on.
msg::MapPoint aheadPoint(double x, double y, double z) {
  msg::MapPoint p;
  p.id = 7;
  p.p_w = Eigen::Vector3d(x, y, z);
  p.normal = p.p_w.normalized().cast<float>();
  p.max_distance = 100;
  p.min_distance = 1;
  return p;
}

// ---------------------------------------------------------------------------------------------------------
// projectIntoFrame

TEST(ProjectIntoFrame, ProjectsWithThePose) {
  const StereoCamera cam = camera();
  const ScalePyramid s(1.2f, 8);
  const Pose3 T_w_c = pose(3, -20, 5, {1, -0.5, 2});
  const Eigen::Vector3d p_c(1.2, -0.7, 9);
  msg::MapPoint p = aheadPoint(0, 0, 1);
  p.p_w = T_w_c * p_c;
  p.normal = (T_w_c.linear() * p_c.normalized()).cast<float>();
  ProjectedPoint pp;
  ASSERT_TRUE(projectIntoFrame(p, T_w_c.inverse(), cam, s, &pp));
  EXPECT_EQ(pp.point, &p);
  EXPECT_NEAR(pp.u, 500 * 1.2 / 9 + 320, 1e-3);
  EXPECT_NEAR(pp.v, 500 * -0.7 / 9 + 240, 1e-3);
  EXPECT_NEAR(pp.u_right, pp.u - 500 * 0.5 / 9, 1e-3);
  EXPECT_NEAR(pp.view_cos, 1, 1e-6);
}

TEST(ProjectIntoFrame, BehindTheCameraIsRejected) {
  const ScalePyramid s(1.2f, 8);
  ProjectedPoint pp;
  msg::MapPoint p = aheadPoint(0, 0, -5);
  p.normal = Eigen::Vector3f(0, 0, 1);
  p.max_distance = 0;  // no range: only the depth rejects it
  EXPECT_FALSE(projectIntoFrame(p, Pose3::Identity(), camera(), s, &pp));
  p.p_w = Eigen::Vector3d(1, 0, 0);  // in the camera plane
  p.normal.setZero();
  EXPECT_FALSE(projectIntoFrame(p, Pose3::Identity(), camera(), s, &pp));
  // The same point is behind a camera turned around.
  p.p_w = Eigen::Vector3d(0, 0, 5);
  EXPECT_TRUE(projectIntoFrame(p, Pose3::Identity(), camera(), s, &pp));
  EXPECT_FALSE(projectIntoFrame(p, pose(0, 180, 0, {0, 0, 0}).inverse(), camera(), s, &pp));
}

TEST(ProjectIntoFrame, OutsideTheImageIsRejected) {
  const StereoCamera cam = camera();
  const ScalePyramid s(1.2f, 8);
  ProjectedPoint pp;
  const double z = 10;
  auto at = [&](double u, double v) {
    msg::MapPoint p = aheadPoint((u - cam.cx) * z / cam.fx, (v - cam.cy) * z / cam.fy, z);
    return projectIntoFrame(p, Pose3::Identity(), cam, s, &pp);
  };
  EXPECT_TRUE(at(0.01, 0.01));
  EXPECT_TRUE(at(639.9, 479.9));
  EXPECT_FALSE(at(-0.1, 100));
  EXPECT_FALSE(at(640, 100));
  EXPECT_FALSE(at(100, -0.1));
  EXPECT_FALSE(at(100, 480));
  EXPECT_FALSE(at(5000, 240));
}

TEST(ProjectIntoFrame, OutsideTheDistanceRangeIsRejected) {
  const ScalePyramid s(1.2f, 8);
  ProjectedPoint pp;
  auto atDistance = [&](double d) {
    msg::MapPoint p = aheadPoint(0, 0, d);
    p.max_distance = 10;
    p.min_distance = 2;
    return projectIntoFrame(p, Pose3::Identity(), camera(), s, &pp);
  };
  // 20 % slack on both sides: [1.6, 12].
  EXPECT_TRUE(atDistance(5));
  EXPECT_TRUE(atDistance(11.9));
  EXPECT_FALSE(atDistance(12.1));
  EXPECT_TRUE(atDistance(1.7));
  EXPECT_FALSE(atDistance(1.5));
  EXPECT_FALSE(atDistance(100));
  // Distance is measured from the camera centre, not along the optical axis only: a camera 3 m back sees
  // the point at 11.5 + 3 m.
  msg::MapPoint p = aheadPoint(0, 0, 11.5);
  p.max_distance = 10;
  p.min_distance = 2;
  EXPECT_TRUE(projectIntoFrame(p, Pose3::Identity(), camera(), s, &pp));
  EXPECT_FALSE(projectIntoFrame(p, pose(0, 0, 0, {0, 0, -3}).inverse(), camera(), s, &pp));
}

TEST(ProjectIntoFrame, ViewingAngleOverSixtyDegreesIsRejected) {
  const ScalePyramid s(1.2f, 8);
  ProjectedPoint pp;
  for (double deg : {0.0, 30.0, 59.0, 61.0, 90.0, 150.0}) {
    msg::MapPoint p = aheadPoint(0, 0, 10);
    p.normal = Eigen::Vector3f(static_cast<float>(std::sin(deg * kDeg)), 0,
                               static_cast<float>(std::cos(deg * kDeg)));
    const bool seen = projectIntoFrame(p, Pose3::Identity(), camera(), s, &pp);
    EXPECT_EQ(seen, deg < 60) << deg << " degrees";
    if (seen) {
      EXPECT_NEAR(pp.view_cos, std::cos(deg * kDeg), 1e-5);
    }
  }
  // Off axis: the ray, not the optical axis, is compared with the normal.
  msg::MapPoint p = aheadPoint(6, 0, 10);
  p.normal = Eigen::Vector3f(0, 0, 1);  // 31 degrees off the ray
  EXPECT_TRUE(projectIntoFrame(p, Pose3::Identity(), camera(), s, &pp));
  p.p_w = Eigen::Vector3d(5, 0, 10);  // ray 26.6 degrees right; normal 90 degrees left of the axis
  p.normal = Eigen::Vector3f(-1, 0, 0);
  EXPECT_FALSE(projectIntoFrame(p, Pose3::Identity(), camera(), s, &pp));
  // No normal (zero): no angle test.
  p.normal.setZero();
  EXPECT_TRUE(projectIntoFrame(p, Pose3::Identity(), camera(), s, &pp));
  EXPECT_EQ(pp.view_cos, 1);
}

TEST(ProjectIntoFrame, PredictedLevel) {
  const ScalePyramid s(1.2f, 8);
  ProjectedPoint pp;
  auto levelAt = [&](double d) {
    msg::MapPoint p = aheadPoint(0, 0, d);
    p.max_distance = 10;
    p.min_distance = 1;
    EXPECT_TRUE(projectIntoFrame(p, Pose3::Identity(), camera(), s, &pp)) << d;
    return pp.level;
  };
  EXPECT_EQ(levelAt(11), 0);  // farther than max_distance: level 0
  EXPECT_EQ(levelAt(10), 0);
  for (int l = 1; l < 8; ++l) EXPECT_EQ(levelAt(10 / std::pow(1.2, l - 0.5)), l) << l;
  EXPECT_EQ(levelAt(10 / std::pow(1.2, 9.5)), 7);  // clamped to the coarsest level (min_distance 1: in range)
  // Without a distance range the level is 0.
  msg::MapPoint p = aheadPoint(0, 0, 3);
  p.max_distance = 0;
  ASSERT_TRUE(projectIntoFrame(p, Pose3::Identity(), camera(), s, &pp));
  EXPECT_EQ(pp.level, 0);
}

// ---------------------------------------------------------------------------------------------------------
// rotationConsistent

std::vector<float> repeat(std::vector<std::pair<float, int>> groups) {
  std::vector<float> v;
  for (auto [a, n] : groups)
    for (int i = 0; i < n; ++i) v.push_back(a + 0.01f * i);
  return v;
}

int kept(const std::vector<uint8_t>& k, size_t from, size_t n) {
  int c = 0;
  for (size_t i = from; i < from + n; ++i) c += k[i];
  return c;
}

TEST(RotationConsistent, KeepsTheThreeMostPopulatedBins) {
  // 12-degree bins: 5 -> bin 0, 100 -> 8, 200 -> 16, 300 -> 25.
  const auto d = repeat({{5, 10}, {100, 8}, {200, 6}, {300, 4}});
  const auto k = rotationConsistent(d);
  ASSERT_EQ(k.size(), d.size());
  EXPECT_EQ(kept(k, 0, 10), 10);
  EXPECT_EQ(kept(k, 10, 8), 8);
  EXPECT_EQ(kept(k, 18, 6), 6);
  EXPECT_EQ(kept(k, 24, 4), 0);
  // Order does not matter: the most populated bin last.
  const auto d2 = repeat({{300, 4}, {200, 6}, {100, 8}, {5, 10}});
  const auto k2 = rotationConsistent(d2);
  EXPECT_EQ(kept(k2, 0, 4), 0);
  EXPECT_EQ(kept(k2, 4, 24), 24);
}

TEST(RotationConsistent, DropsABinBelowTenPercentOfTheLargest) {
  auto k = rotationConsistent(repeat({{50, 20}, {150, 1}, {250, 2}}));
  EXPECT_EQ(kept(k, 0, 20), 20);
  EXPECT_EQ(kept(k, 20, 1), 0);  // 1 < 2
  EXPECT_EQ(kept(k, 21, 2), 2);  // 2 = 10 % of 20 is kept
  k = rotationConsistent(repeat({{50, 30}, {150, 2}, {250, 2}}));
  EXPECT_EQ(kept(k, 30, 4), 0);
}

TEST(RotationConsistent, AnglesWrapAroundAt360) {
  // -5, 355, 715 and -365 are one angle: one bin, the largest.
  const std::vector<float> d = {-5, 355, 715, -365, 354.5f, 40, 80, 120, 160, 200};
  const auto k = rotationConsistent(d);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(k[i], 1) << d[i];
  // 0 and 360 are one angle as well; 359.9 is the bin before it.
  const auto k2 = rotationConsistent({360, 0, 720, -360, 1, 359.9f, 100, 200});
  for (int i = 0; i < 5; ++i) EXPECT_EQ(k2[i], 1) << i;
  // A tiny negative angle rounds to 360 in float: it must still land in a valid bin.
  const auto k3 = rotationConsistent({-1e-6f, -1e-6f, -1e-6f, 359.5f, 100, 200, 250});
  EXPECT_EQ(kept(k3, 0, 4), 4);
}

TEST(RotationConsistent, EmptyAndSingle) {
  EXPECT_TRUE(rotationConsistent({}).empty());
  EXPECT_EQ(rotationConsistent({123}), (std::vector<uint8_t>{1}));
}

TEST(RotationConsistent, AtMostThreeBinsOnTies) {
  const auto k = rotationConsistent(repeat({{6, 5}, {66, 5}, {126, 5}, {186, 5}, {246, 5}}));
  EXPECT_EQ(kept(k, 0, 25), 15);
}

// ---------------------------------------------------------------------------------------------------------
// A synthetic scene: points on a 40-px lattice of the true view at depths 4-30 m, each with a keypoint
// carrying its descriptor (at the level its distance predicts), plus a distractor keypoint 3 px away with a
// far descriptor, plus distractor map points whose descriptors are far from every keypoint.

struct Scene {
  StereoCamera cam = camera();
  ScalePyramid scales{1.2f, 8};
  Pose3 T_w_true = pose(2, 10, -1, {1, 0.2, 3});
  std::vector<msg::MapPoint> points;  // true points, then distractor points
  size_t true_points = 0;
  std::vector<int> level;  // per true point
  std::unordered_map<MapPointId, const msg::MapPoint*> by_id;
  std::mt19937_64 g{12345};
  std::vector<Desc256> issued;

  Scene(const Scene&) = delete;  // by_id points into `points`
  Scene& operator=(const Scene&) = delete;

  Scene() {
    std::mt19937 rng(99);
    auto unit = [&] { return (rng() >> 8) / float(1 << 24); };
    for (int a = 0; a < 15; ++a)
      for (int b = 0; b < 11; ++b) {
        const double u = 30 + 40 * a, v = 30 + 40 * b, z = 4 + 26 * unit();
        const Eigen::Vector3d p_c((u - cam.cx) * z / cam.fx, (v - cam.cy) * z / cam.fy, z);
        msg::MapPoint p;
        p.id = (uint64_t{1} << 56) | (1000 + points.size());
        p.p_w = T_w_true * p_c;
        p.descriptor = freshDescriptor();
        p.normal = (p.p_w - T_w_true.translation()).normalized().cast<float>();
        const int l = static_cast<int>(points.size() % 4);
        const double dist = (p.p_w - T_w_true.translation()).norm();
        p.max_distance = static_cast<float>(dist * std::pow(1.2, l - 0.5));
        p.min_distance = p.max_distance / std::pow(1.2f, 7);
        points.push_back(p);
        level.push_back(l);
      }
    true_points = points.size();
    // Distractor points: near the true ones in space, descriptors far from every true descriptor.
    for (size_t i = 0; i < true_points; i += 3) {
      msg::MapPoint p = points[i];
      p.id = (uint64_t{2} << 56) | (1 + i);
      p.descriptor = freshDescriptor();
      p.p_w += Eigen::Vector3d(0.01, 0.01, 0);
      points.push_back(p);
    }
    for (const auto& p : points) by_id[p.id] = &p;
  }

  /// A descriptor farther than 100 bits (ORB-SLAM2's TH_HIGH) from every one made before: the true points',
  /// the distractor points' and the distractor keypoints' are all distinct.
  Desc256 freshDescriptor() {
    for (;;) {
      const Desc256 d = randomDesc(g);
      bool far = true;
      for (size_t i = 0; i < issued.size() && far; ++i) far = hamming(d, issued[i]) > 100;
      if (far) {
        issued.push_back(d);
        return d;
      }
    }
  }

  const msg::MapPoint* lookup(MapPointId id) const {
    auto it = by_id.find(id);
    return it == by_id.end() ? nullptr : it->second;
  }

  struct Made {
    Frame f;
    std::vector<MapPointId> expected;  // per keypoint: the point it shows, kNoId for a distractor
  };

  /// The true points as seen from `T_w_c` (true keypoints and distractor keypoints), with `f.T_w_c =
  /// predicted`.
  Made frame(const Pose3& T_w_c, const Pose3& predicted, bool stereo = true) {
    Made m;
    std::mt19937 rng(7);
    auto noise = [&] { return ((rng() >> 8) / float(1 << 24) - 0.5f); };  // +-0.5 px
    const Pose3 T_c_w = T_w_c.inverse();
    for (size_t i = 0; i < true_points; ++i) {
      const Eigen::Vector3d p_c = T_c_w * points[i].p_w;
      msg::KeyPoint k;
      k.x = static_cast<float>(cam.fx * p_c.x() / p_c.z() + cam.cx) + noise();
      k.y = static_cast<float>(cam.fy * p_c.y() / p_c.z() + cam.cy) + noise();
      k.octave = static_cast<uint8_t>(level[i]);
      k.angle = static_cast<float>((i * 37) % 360);
      if (stereo && i % 2 == 0) {
        k.right_x = static_cast<float>(k.x - cam.bf() / p_c.z());
        k.depth = static_cast<float>(p_c.z());
      }
      m.f.keypoints.push_back(k);
      m.f.descriptors.push_back(points[i].descriptor);
      m.expected.push_back(points[i].id);
      msg::KeyPoint d = k;  // a distractor next to it, at the same level
      d.x += 3;
      d.y -= 2;
      m.f.keypoints.push_back(d);
      m.f.descriptors.push_back(freshDescriptor());
      m.expected.push_back(kNoId);
    }
    m.f.grid = KeypointGrid(m.f.keypoints, cam.width, cam.height);
    m.f.points.assign(m.f.size(), kNoId);
    m.f.outlier.assign(m.f.size(), 0);
    m.f.T_w_c = predicted;
    return m;
  }

  std::vector<ProjectedPoint> project(const Pose3& T_w_c) const {
    std::vector<ProjectedPoint> out;
    for (const auto& p : points) {
      ProjectedPoint pp;
      if (projectIntoFrame(p, T_w_c.inverse(), cam, scales, &pp)) out.push_back(pp);
    }
    return out;
  }
};

// The prediction is off by 0.2 degrees and 2 cm: up to about 5.5 px with the keypoints' noise.
const Pose3 kOffset = pose(0.2, -0.1, 0.05, {0.02, 0.01, 0.02});

void expectAllRight(const Frame& f, const std::vector<MapPointId>& expected, int matches,
                    int expected_matches) {
  int right = 0;
  for (size_t i = 0; i < f.size(); ++i) {
    if (f.points[i] == kNoId) continue;
    EXPECT_EQ(f.points[i], expected[i]) << "keypoint " << i;
    right += f.points[i] == expected[i];
  }
  EXPECT_EQ(matches, expected_matches);
  EXPECT_EQ(right, expected_matches);
}

TEST(MatchProjectedPoints, EveryPointFindsItsKeypointAndNoDistractorIsMatched) {
  Scene sc;
  const Pose3 predicted = sc.T_w_true * kOffset;
  auto m = sc.frame(sc.T_w_true, predicted);
  const auto pts = sc.project(predicted);
  ASSERT_EQ(pts.size(), sc.points.size()) << "every point should project";
  for (size_t i = 0; i < sc.true_points; ++i) EXPECT_EQ(pts[i].level, sc.level[i]) << i;
  const int n = matchProjectedPoints(m.f, pts, sc.scales, 3);
  expectAllRight(m.f, m.expected, n, static_cast<int>(sc.true_points));
  for (size_t i = 0; i < m.f.size(); ++i) EXPECT_EQ(m.f.outlier[i], 0);
}

TEST(MatchProjectedPoints, MonocularKeypointsAndTightRadius) {
  Scene sc;
  auto m = sc.frame(sc.T_w_true, sc.T_w_true, /*stereo=*/false);
  const int n = matchProjectedPoints(m.f, sc.project(sc.T_w_true), sc.scales, 1);
  expectAllRight(m.f, m.expected, n, static_cast<int>(sc.true_points));
}

TEST(MatchProjectedPoints, RadiusTooSmallForTheOffsetFindsLess) {
  Scene sc;
  const Pose3 predicted = sc.T_w_true * pose(0, 1.5, 0, {0.3, 0, 0});  // ~20-40 px off
  auto m = sc.frame(sc.T_w_true, predicted);
  const int n = matchProjectedPoints(m.f, sc.project(predicted), sc.scales, 1);
  // Whatever it finds must still be right.
  expectAllRight(m.f, m.expected, n, n);
  EXPECT_LT(n, static_cast<int>(sc.true_points) / 2);
}

TEST(MatchProjectedPoints, MatchedKeypointsAreSkippedOutliersAreNot) {
  Scene sc;
  auto m = sc.frame(sc.T_w_true, sc.T_w_true);
  const MapPointId other = (uint64_t{3} << 56) | 1;
  m.f.points[0] = other;  // keypoint 0 (point 0) already matched, trusted
  m.f.points[2] = other;  // keypoint 2 (point 1) matched but rejected by the pose optimisation
  m.f.outlier[2] = 1;
  const int n = matchProjectedPoints(m.f, sc.project(sc.T_w_true), sc.scales, 3);
  EXPECT_EQ(n, static_cast<int>(sc.true_points) - 1);
  EXPECT_EQ(m.f.points[0], other);
  EXPECT_EQ(m.f.points[2], sc.points[1].id);
  EXPECT_EQ(m.f.outlier[2], 0);
  m.expected[0] = other;
  expectAllRight(m.f, m.expected, n + 1, static_cast<int>(sc.true_points));
}

// One point at the image centre and hand-placed keypoints around its projection.
struct OnePoint {
  StereoCamera cam = camera();
  ScalePyramid s{1.2f, 8};
  msg::MapPoint p = aheadPoint(0, 0, 10);
  std::vector<ProjectedPoint> pts;
  Frame f;
  OnePoint(int level) {
    p.max_distance = static_cast<float>(10 * std::pow(1.2, level - 0.5));
    p.min_distance = 0.1f;
    ProjectedPoint pp;
    EXPECT_TRUE(projectIntoFrame(p, Pose3::Identity(), cam, s, &pp));
    EXPECT_EQ(pp.level, level);
    pts.push_back(pp);
  }
  void add(float dx, float dy, int octave, const Desc256& d, float right_x = -1) {
    msg::KeyPoint k;
    k.x = 320 + dx;
    k.y = 240 + dy;
    k.octave = static_cast<uint8_t>(octave);
    k.right_x = right_x;
    f.keypoints.push_back(k);
    f.descriptors.push_back(d);
    f.grid = KeypointGrid(f.keypoints, cam.width, cam.height);
    f.points.assign(f.size(), kNoId);
    f.outlier.assign(f.size(), 0);
  }
  int match(float th = 1) { return matchProjectedPoints(f, pts, s, th); }
};

TEST(MatchProjectedPoints, LevelWindowIsPredictedAndOneBelow) {
  for (int octave = 0; octave < 8; ++octave) {
    OnePoint o(3);
    o.add(0.5f, 0.5f, octave, o.p.descriptor);
    EXPECT_EQ(o.match(1), (octave == 2 || octave == 3) ? 1 : 0) << "octave " << octave;
  }
}

TEST(MatchProjectedPoints, RadiusScalesWithLevelAndViewingAngle) {
  // Head on (view_cos > 0.998): 2.5 px * th * scale; level 2 scale 1.44 -> 3.6 px at th 1.
  OnePoint a(2);
  a.add(3.5f, 0, 2, a.p.descriptor);
  EXPECT_EQ(a.match(1), 1);
  OnePoint b(2);
  b.add(3.7f, 0, 2, b.p.descriptor);
  EXPECT_EQ(b.match(1), 0);
  // Seen 20 degrees off its mean direction: 4 px * 1.44 = 5.76 px.
  OnePoint c(2);
  c.pts[0].view_cos = static_cast<float>(std::cos(20 * kDeg));
  c.add(5.7f, 0, 2, c.p.descriptor);
  EXPECT_EQ(c.match(1), 1);
}

TEST(MatchProjectedPoints, MaxHamming) {
  OnePoint a(0);
  a.add(0, 0, 0, flipBits(a.p.descriptor, 100));
  EXPECT_EQ(a.match(), 1);
  OnePoint b(0);
  b.add(0, 0, 0, flipBits(b.p.descriptor, 101));
  EXPECT_EQ(b.match(), 0);
}

TEST(MatchProjectedPoints, RatioTestOnlyWithinOneLevel) {
  // Best 40, second 45 at the same level: 40 > 0.8 * 45, ambiguous.
  OnePoint a(1);
  a.add(0, 0, 1, flipBits(a.p.descriptor, 40));
  a.add(1, 0, 1, flipBits(a.p.descriptor, 45, 3));
  EXPECT_EQ(a.match(), 0);
  // The same two at different levels: accepted (ORB-SLAM2).
  OnePoint b(1);
  b.add(0, 0, 1, flipBits(b.p.descriptor, 40));
  b.add(1, 0, 0, flipBits(b.p.descriptor, 45, 3));
  EXPECT_EQ(b.match(), 1);
  EXPECT_EQ(b.f.points[0], b.p.id);
  // Clearly better than the second at the same level: accepted.
  OnePoint c(1);
  c.add(0, 0, 1, flipBits(c.p.descriptor, 20));
  c.add(1, 0, 1, flipBits(c.p.descriptor, 45, 3));
  EXPECT_EQ(c.match(), 1);
  EXPECT_EQ(c.f.points[0], c.p.id);
}

TEST(MatchProjectedPoints, StereoKeypointMustAgreeInTheRightImage) {
  // u_right = 320 - 250 / 10 = 295; radius 2.5 px at level 0.
  OnePoint a(0);
  a.add(0, 0, 0, a.p.descriptor, 296);
  EXPECT_EQ(a.match(), 1);
  OnePoint b(0);
  b.add(0, 0, 0, b.p.descriptor, 290);
  EXPECT_EQ(b.match(), 0);
}

// ---------------------------------------------------------------------------------------------------------
// matchFromLastFrame

struct TwoFrames {
  Scene sc;
  Pose3 T_w_last, T_w_cur;
  Scene::Made last, cur;
  std::function<const msg::MapPoint*(MapPointId)> lookup;
  TwoFrames(const TwoFrames&) = delete;  // lookup captures this
  TwoFrames& operator=(const TwoFrames&) = delete;

  // `step`: the true motion from the last frame to the current one (in the last camera's frame).
  explicit TwoFrames(const Pose3& step = pose(0, 0.5, 0, {0.05, 0, 0.3}), bool stereo = true) {
    T_w_cur = sc.T_w_true;
    T_w_last = T_w_cur * step.inverse();
    last = sc.frame(T_w_last, T_w_last, stereo);
    cur = sc.frame(T_w_cur, T_w_cur * kOffset, stereo);
    for (size_t i = 0; i < last.f.size(); ++i) last.f.points[i] = last.expected[i];
    // The keypoints turned by 10 degrees between the frames (a consistent rotation).
    for (size_t i = 0; i < cur.f.size(); ++i) cur.f.keypoints[i].angle = last.f.keypoints[i].angle - 10;
    lookup = [this](MapPointId id) { return sc.lookup(id); };
  }
  int match(float th = 7, bool check_rotation = true) {
    ProjectionParams p;
    p.check_rotation = check_rotation;
    return matchFromLastFrame(cur.f, last.f, lookup, sc.cam, sc.scales, th, p);
  }
};

TEST(MatchFromLastFrame, EveryPointFindsItsKeypointAndNoDistractorIsMatched) {
  TwoFrames t;
  const int n = t.match();
  expectAllRight(t.cur.f, t.cur.expected, n, static_cast<int>(t.sc.true_points));
}

TEST(MatchFromLastFrame, Monocular) {
  TwoFrames t(pose(0, 0.5, 0, {0.05, 0, 0.3}), /*stereo=*/false);
  const int n = t.match();
  expectAllRight(t.cur.f, t.cur.expected, n, static_cast<int>(t.sc.true_points));
}

TEST(MatchFromLastFrame, SkipsUnmatchedOutlierAndUnknownPoints) {
  TwoFrames t;
  t.last.f.points[0] = kNoId;                     // point 0: not matched in the last frame
  t.last.f.outlier[2] = 1;                        // point 1: an outlier there
  t.last.f.points[4] = (uint64_t{3} << 56) | 99;  // point 2: a point the map no longer has
  // Distractor keypoints of the last frame matched to distractor points: their descriptors are far.
  t.last.f.points[7] = t.sc.points[t.sc.true_points].id;
  const int n = t.match();
  for (int i : {0, 2, 4}) {
    EXPECT_EQ(t.cur.f.points[i], kNoId) << i;
    t.cur.expected[i] = kNoId;
  }
  expectAllRight(t.cur.f, t.cur.expected, n, static_cast<int>(t.sc.true_points) - 3);
}

TEST(MatchFromLastFrame, AlreadyMatchedKeypointsAreNotTaken) {
  TwoFrames t;
  const MapPointId other = (uint64_t{3} << 56) | 1;
  t.cur.f.points[0] = other;
  const int n = t.match();
  EXPECT_EQ(t.cur.f.points[0], other);
  t.cur.expected[0] = other;
  expectAllRight(t.cur.f, t.cur.expected, n + 1, static_cast<int>(t.sc.true_points));
}

TEST(MatchFromLastFrame, RotationCheckDropsInconsistentMatches) {
  TwoFrames t;
  // Five keypoints turned the other way: angle difference 180 + 10 degrees instead of 10.
  std::vector<size_t> odd;
  for (size_t i = 0; i < 5; ++i) {
    const size_t k = 2 * (10 * i + 3);
    t.cur.f.keypoints[k].angle = t.last.f.keypoints[k].angle - 190;
    odd.push_back(k);
  }
  TwoFrames u;  // the same frames (all seeded), matched without the check
  for (size_t k : odd) u.cur.f.keypoints[k].angle = u.last.f.keypoints[k].angle - 190;
  const int n = t.match();
  for (size_t k : odd) {
    EXPECT_EQ(t.cur.f.points[k], kNoId) << k;
    t.cur.expected[k] = kNoId;
  }
  expectAllRight(t.cur.f, t.cur.expected, n, static_cast<int>(t.sc.true_points) - 5);
  const int all = u.match(7, /*check_rotation=*/false);
  expectAllRight(u.cur.f, u.cur.expected, all, static_cast<int>(u.sc.true_points));
}

// One point 10 m ahead of the last camera, seen at octave 3 there; the current keypoint at `octave`.
int matchAfterMotion(double forward_m, int octave) {
  const StereoCamera cam = camera();
  const ScalePyramid s(1.2f, 8);
  msg::MapPoint p = aheadPoint(0, 0, 10);
  p.descriptor.w = {1, 2, 3, 4};
  Frame last, cur;
  msg::KeyPoint k;
  k.x = 320;
  k.y = 240;
  k.octave = 3;
  last.keypoints = {k};
  last.descriptors = {p.descriptor};
  last.points = {p.id};
  last.outlier = {0};
  last.grid = KeypointGrid(last.keypoints, cam.width, cam.height);
  k.octave = static_cast<uint8_t>(octave);
  k.x += 0.5f;
  cur.keypoints = {k};
  cur.descriptors = {p.descriptor};
  cur.points = {kNoId};
  cur.outlier = {0};
  cur.grid = KeypointGrid(cur.keypoints, cam.width, cam.height);
  cur.T_w_c = pose(0, 0, 0, {0, 0, forward_m});
  return matchFromLastFrame(
      cur, last, [&](MapPointId) { return &p; }, cam, s, 7);
}

TEST(MatchFromLastFrame, LevelsFollowTheDirectionOfMotion) {
  // Forward by more than a baseline (0.5 m): the point looks bigger, so same or coarser levels.
  for (int o = 0; o < 8; ++o) EXPECT_EQ(matchAfterMotion(2, o), o >= 3 ? 1 : 0) << "forward, octave " << o;
  // Backward: same or finer.
  for (int o = 0; o < 8; ++o) EXPECT_EQ(matchAfterMotion(-2, o), o <= 3 ? 1 : 0) << "backward, octave " << o;
  // Less than a baseline either way: one level around.
  for (int o = 0; o < 8; ++o)
    EXPECT_EQ(matchAfterMotion(0.2, o), (o >= 2 && o <= 4) ? 1 : 0) << "octave " << o;
}

// ---------------------------------------------------------------------------------------------------------
// matchByDescriptor

TEST(MatchByDescriptor, EveryPointFindsItsKeypointAndNoDistractorIsMatched) {
  TwoFrames t;
  // Without a pose, positions do not matter: a few bits differ, as between two real views.
  for (size_t i = 0; i < t.cur.f.size(); i += 2)
    t.cur.f.descriptors[i] = flipBits(t.cur.f.descriptors[i], 8, static_cast<int>(i));
  // Distractor points in the last frame (their keypoints' descriptors are far from everything).
  for (size_t i = 1; i < t.last.f.size(); i += 10) t.last.f.points[i] = t.sc.points[t.sc.true_points].id;
  const int n = matchByDescriptor(t.cur.f, t.last.f, t.lookup);
  expectAllRight(t.cur.f, t.cur.expected, n, static_cast<int>(t.sc.true_points));
}

TEST(MatchByDescriptor, TakesTheIdTheLookupGives) {
  // The last frame still names a point that was fused: the current frame gets the kept point's id.
  TwoFrames t;
  const MapPointId stale = (uint64_t{3} << 56) | 5;
  t.last.f.points[0] = stale;
  auto lookup = [&](MapPointId id) { return id == stale ? &t.sc.points[7] : t.sc.lookup(id); };
  matchByDescriptor(t.cur.f, t.last.f, lookup);
  EXPECT_EQ(t.cur.f.points[0], t.sc.points[7].id);
}

TEST(MatchByDescriptor, StrictThresholdRatioAndSkips) {
  TwoFrames t;
  const int N = static_cast<int>(t.sc.true_points);
  t.cur.f.descriptors[0] = flipBits(t.cur.f.descriptors[0], 51);  // point 0: too far (> 50)
  t.cur.f.descriptors[2] = flipBits(t.cur.f.descriptors[2], 50);  // point 1: just in
  // Point 2: its keypoint and the distractor beside it both close (20 and 25 bits): 20 > 0.7 * 25.
  t.cur.f.descriptors[4] = flipBits(t.last.f.descriptors[4], 20);
  t.cur.f.descriptors[5] = flipBits(t.last.f.descriptors[4], 25, 100);
  t.last.f.outlier[6] = 1;                        // point 3: outlier in the last frame
  t.last.f.points[8] = (uint64_t{3} << 56) | 99;  // point 4: unknown to the map
  const int n = matchByDescriptor(t.cur.f, t.last.f, t.lookup);
  for (int k : {0, 4, 5, 6, 8}) {
    EXPECT_EQ(t.cur.f.points[k], kNoId) << k;
    t.cur.expected[k] = kNoId;
  }
  EXPECT_EQ(t.cur.f.points[2], t.sc.points[1].id);
  expectAllRight(t.cur.f, t.cur.expected, n, N - 4);
}

TEST(MatchByDescriptor, AKeypointClaimedTwiceKeepsTheCloserClaim) {
  TwoFrames t;
  // Last keypoints 0 (point 0) and 2 (point 1) both carry descriptors near current keypoint 0's; point 1's
  // own keypoint in the current frame is made far, so keypoint 0 is the best for both.
  const Desc256 base = t.cur.f.descriptors[0];
  t.last.f.descriptors[0] = flipBits(base, 10);
  t.last.f.descriptors[2] = flipBits(base, 4, 200);
  t.cur.f.descriptors[2] = t.sc.freshDescriptor();
  // The current keypoint turned as the others did relative to last keypoint 2 (else the rotation check,
  // not the claim, would decide).
  t.cur.f.keypoints[0].angle = t.last.f.keypoints[2].angle - 10;
  const int n = matchByDescriptor(t.cur.f, t.last.f, t.lookup);
  EXPECT_EQ(t.cur.f.points[0], t.sc.points[1].id);  // the closer claim (4 bits)
  EXPECT_EQ(t.cur.f.points[2], kNoId);
  t.cur.expected[0] = t.sc.points[1].id;
  t.cur.expected[2] = kNoId;
  expectAllRight(t.cur.f, t.cur.expected, n, static_cast<int>(t.sc.true_points) - 1);
}

TEST(MatchByDescriptor, RotationCheckDropsInconsistentMatches) {
  TwoFrames t;
  for (size_t k : {0, 20, 40, 60}) t.cur.f.keypoints[k].angle = t.last.f.keypoints[k].angle - 190;
  const int n = matchByDescriptor(t.cur.f, t.last.f, t.lookup);
  for (size_t k : {0, 20, 40, 60}) {
    EXPECT_EQ(t.cur.f.points[k], kNoId) << k;
    t.cur.expected[k] = kNoId;
  }
  expectAllRight(t.cur.f, t.cur.expected, n, static_cast<int>(t.sc.true_points) - 4);
}

}  // namespace
}  // namespace binloop
