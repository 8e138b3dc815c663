#include "binloop/mapping/epipolar_matcher.h"

#include <algorithm>
#include <cmath>
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

namespace {

// b's candidate keypoints binned in square cells, so that a keypoint of a visits only the cells its epipolar
// band crosses instead of every candidate (the line test over all pairs was a tenth of mapping's time).
class BandGrid {
 public:
  static constexpr double kCell = 32;  // px

  BandGrid(const std::vector<msg::KeyPoint>& kps, const std::vector<int>& ids) {
    double max_x = 0, max_y = 0;
    if (!ids.empty()) {
      x0_ = max_x = kps[ids[0]].x;
      y0_ = max_y = kps[ids[0]].y;
    }
    for (int j : ids) {
      x0_ = std::min<double>(x0_, kps[j].x);
      y0_ = std::min<double>(y0_, kps[j].y);
      max_x = std::max<double>(max_x, kps[j].x);
      max_y = std::max<double>(max_y, kps[j].y);
    }
    cols_ = static_cast<int>((max_x - x0_) / kCell) + 1;
    rows_ = static_cast<int>((max_y - y0_) / kCell) + 1;
    start_.assign(static_cast<size_t>(cols_) * rows_ + 1, 0);
    for (int j : ids) ++start_[cellOf(kps[j]) + 1];
    for (size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
    ids_.resize(ids.size());
    std::vector<int> fill(start_.begin(), start_.end() - 1);
    for (int j : ids) ids_[fill[cellOf(kps[j])]++] = j;
  }

  /// Calls visit(j) for every candidate in a cell that the band |l . (x, y, 1)| / |l.xy| < half_width
  /// crosses (and some beside it): a superset of the candidates within the band. l.xy must not be zero.
  template <class Visit>
  void forBand(const Eigen::Vector3d& l, double half_width, Visit&& visit) const {
    // In grid coordinates (origin at the first cell's corner) the line's offset changes.
    const double lz = l.z() + l.x() * x0_ + l.y() * y0_;
    const bool by_columns = std::abs(l.y()) >= std::abs(l.x());
    // Along the line's flatter axis u, the other coordinate w = -(l_u u + l_z) / l_w, widened by the band.
    const double lu = by_columns ? l.x() : l.y(), lw = by_columns ? l.y() : l.x();
    const double slack = half_width * std::hypot(l.x(), l.y()) / std::abs(lw);
    const int n_u = by_columns ? cols_ : rows_, n_w = by_columns ? rows_ : cols_;
    for (int u = 0; u < n_u; ++u) {
      const double w0 = -(lu * u * kCell + lz) / lw, w1 = -(lu * (u + 1) * kCell + lz) / lw;
      const double lo = std::min(w0, w1) - slack, hi = std::max(w0, w1) + slack;
      if (hi < 0 || lo >= n_w * kCell) continue;
      const int first = std::max(0, static_cast<int>(std::floor(lo / kCell)));
      const int last = std::min(n_w - 1, static_cast<int>(std::floor(hi / kCell)));
      for (int w = first; w <= last; ++w) {
        const size_t c = by_columns ? static_cast<size_t>(w) * cols_ + u : static_cast<size_t>(u) * cols_ + w;
        for (int k = start_[c]; k < start_[c + 1]; ++k) visit(ids_[k]);
      }
    }
  }

 private:
  size_t cellOf(const msg::KeyPoint& k) const {
    const int cx = std::min(cols_ - 1, static_cast<int>((k.x - x0_) / kCell));
    const int cy = std::min(rows_ - 1, static_cast<int>((k.y - y0_) / kCell));
    return static_cast<size_t>(cy) * cols_ + cx;
  }
  double x0_ = 0, y0_ = 0;  // the least candidate coordinates: the first cell's corner
  int cols_ = 1, rows_ = 1;
  std::vector<int> start_, ids_;  // candidates by cell: ids_[start_[c] .. start_[c + 1])
};

}  // namespace

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
  const BandGrid grid(kb, cand_b);
  // The widest band the top level allows: the grid only has to give a superset, `consider` decides.
  const double half_width = std::sqrt(p.line_chi2 * static_cast<double>(s.sigma2.back())) + 1e-3;

  constexpr int kNone = -1;
  std::vector<int> best_of_a(ka.size(), kNone);
  std::vector<int> best_of_b(kb.size(), kNone), dist_of_b(kb.size(), std::numeric_limits<int>::max());
  for (size_t i = 0; i < ka.size(); ++i) {
    if ((*a.point_ids)[i] != kNoId) continue;
    const msg::KeyPoint& k1 = ka[i];
    const bool stereo1 = k1.right_x >= 0;
    const Eigen::Vector3d l = F * Eigen::Vector3d(k1.x, k1.y, 1);
    const double inv_norm2 = 1.0 / (l.x() * l.x() + l.y() * l.y());
    int best = std::numeric_limits<int>::max(), best_j = kNone;
    // The best distance, ties to the lowest index: the cells are visited in no index order.
    auto consider = [&](int j) {
      const msg::KeyPoint& k2 = kb[j];
      const double d = l.x() * k2.x + l.y() * k2.y + l.z();
      if (d * d * inv_norm2 >= p.line_chi2 * s.sigma2[k2.octave]) return;
      if (!stereo1 && k2.right_x < 0 && epipole_in_front) {
        const double dx = ex - k2.x, dy = ey - k2.y;
        const double r = p.epipole_px * s.scale[k2.octave];
        if (dx * dx + dy * dy < r * r) return;
      }
      const int h = hamming((*a.descriptors)[i], (*b.descriptors)[j]);
      if (h < best || (h == best && j < best_j)) best = h, best_j = j;
    };
    if (std::isfinite(inv_norm2)) {
      grid.forBand(l, half_width, consider);
    } else {  // no line (the poses coincide): the test above decides for every candidate, as it would
      for (int j : cand_b) consider(j);
    }
    if (best_j == kNone || best > p.max_hamming) continue;
    best_of_a[i] = best_j;
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
