#include "binloop/mapping/epipolar_matcher.h"

#include <limits>

#include "binloop/map/point_projection.h"

namespace binloop {

namespace {

Eigen::Matrix3d intrinsics(const StereoCamera& c) {
  Eigen::Matrix3d K;
  K << c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1;
  return K;
}

}  // namespace

Eigen::Matrix3d fundamentalMatrix(const Pose3& T_w_a, const Pose3& T_w_b, const StereoCamera& cam) {
  const Pose3 T_b_a = T_w_b.inverse() * T_w_a;
  const Eigen::Matrix3d K_inv = intrinsics(cam).inverse();
  return K_inv.transpose() * skew(T_b_a.translation()) * T_b_a.linear() * K_inv;
}

std::vector<std::pair<int, int>> matchAlongEpipolarLines(const EpipolarView& a, const EpipolarView& b,
                                                         const ScalePyramid& s, const EpipolarParams& p) {
  const Eigen::Matrix3d F = fundamentalMatrix(*a.T_w_c, *b.T_w_c, *b.camera);
  // Where a's camera centre appears in b.
  const Eigen::Vector3d c_b = b.T_w_c->inverse() * a.T_w_c->translation();
  const bool epipole_in_front = c_b.z() > 0;
  const Eigen::Vector2d e = b.camera->project(c_b);
  const double ex = e.x(), ey = e.y();

  const auto& ka = *a.keypoints;
  const auto& kb = *b.keypoints;
  std::vector<int> cand_b;
  for (size_t j = 0; j < kb.size(); ++j)
    if ((*b.point_ids)[j] == kNoId) cand_b.push_back(static_cast<int>(j));

  constexpr int kNone = -1;
  std::vector<int> best_of_a(ka.size(), kNone), dist_of_a(ka.size(), std::numeric_limits<int>::max());
  std::vector<int> best_of_b(kb.size(), kNone), dist_of_b(kb.size(), std::numeric_limits<int>::max());
  for (size_t i = 0; i < ka.size(); ++i) {
    if ((*a.point_ids)[i] != kNoId) continue;
    const msg::KeyPoint& k1 = ka[i];
    const bool stereo1 = k1.right_x >= 0;
    const Eigen::Vector3d l = F * Eigen::Vector3d(k1.x, k1.y, 1);
    const double inv_norm2 = 1.0 / (l.x() * l.x() + l.y() * l.y());
    int best = std::numeric_limits<int>::max(), best_j = kNone;
    for (int j : cand_b) {
      const msg::KeyPoint& k2 = kb[j];
      const double d = l.x() * k2.x + l.y() * k2.y + l.z();
      if (d * d * inv_norm2 >= p.line_chi2 * s.sigma2[k2.octave]) continue;
      if (!stereo1 && k2.right_x < 0 && epipole_in_front) {
        const double dx = ex - k2.x, dy = ey - k2.y;
        const double r = p.epipole_px * s.scale[k2.octave];
        if (dx * dx + dy * dy < r * r) continue;
      }
      const int h = hamming((*a.descriptors)[i], (*b.descriptors)[j]);
      if (h < best) best = h, best_j = j;
    }
    if (best_j == kNone || best > p.max_hamming) continue;
    best_of_a[i] = best_j;
    dist_of_a[i] = best;
    if (best < dist_of_b[best_j]) dist_of_b[best_j] = best, best_of_b[best_j] = static_cast<int>(i);
  }
  std::vector<std::pair<int, int>> pairs;
  std::vector<float> angle_diff;
  for (size_t i = 0; i < ka.size(); ++i) {
    const int j = best_of_a[i];
    if (j == kNone || best_of_b[j] != static_cast<int>(i)) continue;
    pairs.emplace_back(static_cast<int>(i), j);
    angle_diff.push_back(ka[i].angle - kb[j].angle);
  }
  if (!p.check_rotation || pairs.empty()) return pairs;
  const std::vector<uint8_t> keep = rotationConsistent(angle_diff);
  std::vector<std::pair<int, int>> out;
  for (size_t k = 0; k < pairs.size(); ++k)
    if (keep[k]) out.push_back(pairs[k]);
  return out;
}

}  // namespace binloop
