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

// Every pair tested, ties to the lower index: what the binned search must give, pair for pair.
std::vector<std::pair<int, int>> everyPair(const EpipolarView& a, const EpipolarView& b,
                                           const ScalePyramid& s, const EpipolarParams& p) {
  const Eigen::Matrix3d F = fundamentalMatrix(*a.T_w_c, *b.T_w_c, *b.camera);
  const Eigen::Vector3d c_b = b.T_w_c->inverse() * a.T_w_c->translation();
  const Eigen::Vector2d e = b.camera->project(c_b);
  const auto &ka = *a.keypoints, &kb = *b.keypoints;
  std::vector<int> best_of_a(ka.size(), -1), best_of_b(kb.size(), -1), dist_of_b(kb.size(), 1 << 30);
  for (size_t i = 0; i < ka.size(); ++i) {
    if ((*a.point_ids)[i] != kNoId) continue;
    const Eigen::Vector3d l = F * Eigen::Vector3d(ka[i].x, ka[i].y, 1);
    int best = 1 << 30, best_j = -1;
    for (size_t j = 0; j < kb.size(); ++j) {
      if ((*b.point_ids)[j] != kNoId) continue;
      const double d = l.x() * kb[j].x + l.y() * kb[j].y + l.z();
      if (d * d / (l.x() * l.x() + l.y() * l.y()) >= p.line_chi2 * s.sigma2[kb[j].octave]) continue;
      if (ka[i].right_x < 0 && kb[j].right_x < 0 && c_b.z() > 0 &&
          (e - Eigen::Vector2d(kb[j].x, kb[j].y)).norm() < p.epipole_px * s.scale[kb[j].octave])
        continue;
      const int h = hamming((*a.descriptors)[i], (*b.descriptors)[j]);
      if (h < best) best = h, best_j = static_cast<int>(j);
    }
    if (best_j < 0 || best > p.max_hamming) continue;
    best_of_a[i] = best_j;
    if (best < dist_of_b[best_j]) dist_of_b[best_j] = best, best_of_b[best_j] = static_cast<int>(i);
  }
  std::vector<std::pair<int, int>> pairs;
  for (size_t i = 0; i < ka.size(); ++i)
    if (best_of_a[i] >= 0 && best_of_b[best_of_a[i]] == static_cast<int>(i))
      pairs.emplace_back(static_cast<int>(i), best_of_a[i]);
  return pairs;
}

// Keypoints all over both images at every level, descriptors drawn from a few so that ties are common; the
// second camera moved forward (the epipole in the image, lines at every angle), sideways, up, or not at all.
TEST(EpipolarMatcher, TheBinnedSearchGivesWhatTestingEveryPairGives) {
  const StereoCamera cam = test::kitti();
  const ScalePyramid scales{1.2f, 8};
  EpipolarParams p;
  p.check_rotation = false;  // compare the matching itself
  p.max_hamming = 90;
  HashRng rng(11);
  std::vector<Desc256> pool;
  for (int k = 0; k < 12; ++k) pool.push_back(randomDescriptor(rng));
  auto keypoints = [&](std::vector<msg::KeyPoint>* kps, Descriptors* desc, std::vector<MapPointId>* ids) {
    for (int n = 0; n < 1500; ++n) {
      msg::KeyPoint k{static_cast<float>(rng.uniform(0, cam.width - 1)),
                      static_cast<float>(rng.uniform(0, cam.height - 1)),
                      0.f,
                      static_cast<uint8_t>(rng.uniform(0, 7.99)),
                      -1.f,
                      -1.f};
      if (rng.chance(0.5)) k.right_x = k.x - 10.f;
      kps->push_back(k);
      desc->push_back(flipBits(pool[static_cast<size_t>(rng.uniform(0, 11.99))], 20, rng));
      ids->push_back(rng.chance(0.2) ? MapPointId{7} : kNoId);
    }
  };
  const Eigen::Vector3d moves[] = {{0.1, 0, 1.5}, {1.5, 0.1, 0.2}, {0, 1.2, 0.1}, {0, 0, 0}, {-0.3, 0.2, -1}};
  for (const Eigen::Vector3d& t : moves) {
    View a, b;
    a.T_w_c = Pose3::Identity();
    b.T_w_c = Pose3::Identity();
    b.T_w_c.linear() = Eigen::AngleAxisd(0.05, Eigen::Vector3d(0.2, 1, 0.1).normalized()).toRotationMatrix();
    b.T_w_c.translation() = t;
    keypoints(&a.kps, &a.desc, &a.ids);
    keypoints(&b.kps, &b.desc, &b.ids);
    const auto expected = everyPair(a.view(cam), b.view(cam), scales, p);
    EXPECT_GT(expected.size(), 50u) << "move " << t.transpose();
    EXPECT_EQ(matchAlongEpipolarLines(a.view(cam), b.view(cam), scales, p), expected)
        << "move " << t.transpose();
  }
}

}  // namespace
}  // namespace binloop
