#include "binloop/tracking/projection_search.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace binloop {

int matchProjectedPoints(Frame& f, const std::vector<ProjectedPoint>& pts, const ScalePyramid& s, float th,
                         const ProjectionParams& p) {
  int matches = 0;
  for (const ProjectedPoint& pp : pts) {
    const float r = th * (pp.view_cos > 0.998f ? 2.5f : 4.0f) * s.scale[pp.level];
    const std::vector<int> near = f.grid.near(pp.u, pp.v, r, pp.level - 1, pp.level);
    int best = std::numeric_limits<int>::max(), second = best, best_idx = -1, best_level = -1,
        second_level = -1;
    for (int i : near) {
      if (f.points[i] != kNoId && !f.outlier[i]) continue;
      const msg::KeyPoint& k = f.keypoints[i];
      if (k.right_x >= 0 && std::abs(pp.u_right - k.right_x) > r) continue;
      const int d = hamming(pp.point->descriptor, f.descriptors[i]);
      if (d < best) {
        second = best;
        second_level = best_level;
        best = d;
        best_idx = i;
        best_level = k.octave;
      } else if (d < second) {
        second = d;
        second_level = k.octave;
      }
    }
    if (best_idx < 0 || best > p.max_hamming) continue;
    if (best_level == second_level && best > p.ratio * second) continue;
    f.points[best_idx] = pp.point->id;
    f.outlier[best_idx] = 0;
    ++matches;
  }
  return matches;
}

int matchFromLastFrame(Frame& cur, const Frame& last,
                       const std::function<const msg::MapPoint*(MapPointId)>& lookup, const StereoCamera& cam,
                       const ScalePyramid& s, float th, const ProjectionParams& p) {
  const Pose3 T_c_w = cur.T_w_c.inverse();
  // Moving forward by more than a baseline, points look bigger and are found at the same or coarser levels;
  // moving backward, at the same or finer ones (ORB-SLAM2's bForward / bBackward).
  const Eigen::Vector3d t_lc = (last.T_w_c.inverse() * cur.T_w_c).translation();
  const bool forward = t_lc.z() > cam.baseline_m;
  const bool backward = -t_lc.z() > cam.baseline_m;
  std::vector<int> matched_kp;
  std::vector<float> diffs;
  for (size_t i = 0; i < last.size(); ++i) {
    if (last.points[i] == kNoId || last.outlier[i]) continue;
    const msg::MapPoint* mp = lookup(last.points[i]);
    if (!mp) continue;
    const Eigen::Vector3d p_c = T_c_w * mp->p_w;
    if (p_c.z() <= 0) continue;
    const Eigen::Vector2d uv = cam.project(p_c);
    const float u = static_cast<float>(uv.x()), v = static_cast<float>(uv.y());
    if (u < 0 || u >= cam.width || v < 0 || v >= cam.height) continue;
    const int oct = last.keypoints[i].octave;
    const float r = th * s.scale[oct];
    std::vector<int> near = forward    ? cur.grid.near(u, v, r, oct, -1)
                            : backward ? cur.grid.near(u, v, r, 0, oct)
                                       : cur.grid.near(u, v, r, std::max(0, oct - 1), oct + 1);
    const float ur = static_cast<float>(u - cam.bf() / p_c.z());
    int best = std::numeric_limits<int>::max(), best_idx = -1;
    for (int j : near) {
      if (cur.points[j] != kNoId) continue;
      const msg::KeyPoint& k = cur.keypoints[j];
      if (k.right_x >= 0 && std::abs(ur - k.right_x) > r) continue;
      const int d = hamming(mp->descriptor, cur.descriptors[j]);
      if (d < best) {
        best = d;
        best_idx = j;
      }
    }
    if (best_idx < 0 || best > p.max_hamming) continue;
    cur.points[best_idx] = mp->id;
    cur.outlier[best_idx] = 0;
    matched_kp.push_back(best_idx);
    diffs.push_back(last.keypoints[i].angle - cur.keypoints[best_idx].angle);
  }
  int n = static_cast<int>(matched_kp.size());
  if (p.check_rotation) {
    const std::vector<uint8_t> keep = rotationConsistent(diffs);
    for (size_t k = 0; k < matched_kp.size(); ++k) {
      if (!keep[k]) {
        cur.points[matched_kp[k]] = kNoId;
        --n;
      }
    }
  }
  return n;
}

int matchByDescriptor(Frame& cur, const Frame& last,
                      const std::function<const msg::MapPoint*(MapPointId)>& lookup, int max_hamming_strict,
                      float ratio) {
  // Best current keypoint for each last-frame point; a keypoint claimed twice keeps the closer claim.
  std::vector<int> claim_dist(cur.size(), std::numeric_limits<int>::max());
  std::vector<int> claim_from(cur.size(), -1);
  for (size_t i = 0; i < last.size(); ++i) {
    if (last.points[i] == kNoId || last.outlier[i] || !lookup(last.points[i])) continue;
    const Desc256& d = last.descriptors[i];
    int best = std::numeric_limits<int>::max(), second = best, best_j = -1;
    for (size_t j = 0; j < cur.size(); ++j) {
      const int dist = hamming(d, cur.descriptors[j]);
      if (dist < best) {
        second = best;
        best = dist;
        best_j = static_cast<int>(j);
      } else if (dist < second) {
        second = dist;
      }
    }
    if (best_j < 0 || best > max_hamming_strict || best > ratio * second) continue;
    if (best < claim_dist[best_j]) {
      claim_dist[best_j] = best;
      claim_from[best_j] = static_cast<int>(i);
    }
  }
  std::vector<int> matched;
  std::vector<float> diffs;
  for (size_t j = 0; j < cur.size(); ++j) {
    if (claim_from[j] < 0) continue;
    matched.push_back(static_cast<int>(j));
    diffs.push_back(last.keypoints[claim_from[j]].angle - cur.keypoints[j].angle);
  }
  const std::vector<uint8_t> keep = rotationConsistent(diffs);
  int n = 0;
  for (size_t k = 0; k < matched.size(); ++k) {
    if (!keep[k]) continue;
    const int j = matched[k];
    cur.points[j] = lookup(last.points[claim_from[j]])->id;
    cur.outlier[j] = 0;
    ++n;
  }
  return n;
}

}  // namespace binloop
