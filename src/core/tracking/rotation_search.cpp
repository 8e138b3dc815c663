#include "binloop/tracking/rotation_search.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

#include "binloop/util/hash_random.h"

namespace binloop {

Eigen::Matrix3d rotationBetweenBearings(const std::vector<Eigen::Vector3d>& obs,
                                        const std::vector<Eigen::Vector3d>& pred) {
  if (obs.size() < 2 || obs.size() != pred.size()) return Eigen::Matrix3d::Identity();
  Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < obs.size(); ++i) M += obs[i] * pred[i].transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  // A reflection fits mirrored bearings as well; the sign fix keeps a proper rotation.
  D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1 : 1;
  return svd.matrixU() * D * svd.matrixV().transpose();
}

namespace {

struct Pair {
  Eigen::Vector3d obs, pred;  // unit bearings in the camera: the keypoint's, the point's at the prediction
  double tol;                 // angle (rad) within which they agree, by the keypoint's level
};

int countInliers(const std::vector<Pair>& pairs, const Eigen::Matrix3d& R, std::vector<uint8_t>* in) {
  int n = 0;
  if (in) in->assign(pairs.size(), 0);
  for (size_t i = 0; i < pairs.size(); ++i) {
    if ((pairs[i].obs - R * pairs[i].pred).norm() > pairs[i].tol) continue;
    ++n;
    if (in) (*in)[i] = 1;
  }
  return n;
}

}  // namespace

RotationSearchResult searchRotation(const Frame& f, const Pose3& predicted_T_w_c,
                                    const std::vector<const msg::MapPoint*>& points, const StereoCamera& cam,
                                    const ScalePyramid& s, const RotationSearchParams& p, uint64_t seed) {
  RotationSearchResult out;
  const Pose3 T_c_w = predicted_T_w_c.inverse();
  const double window = cam.fx * std::tan(p.max_angle_deg * M_PI / 180.0);
  auto bearing = [&cam](double u, double v) {
    return Eigen::Vector3d((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0).normalized();
  };
  std::vector<Pair> pairs;
  for (const msg::MapPoint* mp : points) {
    const Eigen::Vector3d c = T_c_w * mp->p_w;
    const double dist = c.norm();
    // In front of the camera by more than the rotation's doubt allows to swing behind it.
    if (dist < p.min_distance_m || c.z() < dist * std::cos((90.0 - p.max_angle_deg) * M_PI / 180.0)) continue;
    const Eigen::Vector2d uv = cam.project(c);
    const double u = uv.x(), v = uv.y();
    if (u < -window || v < -window || u > cam.width + window || v > cam.height + window) continue;
    const int level = s.predictLevel(mp->max_distance, static_cast<float>(dist));
    int best = p.max_hamming + 1, best_j = -1;
    for (int j : f.grid.near(static_cast<float>(u), static_cast<float>(v), static_cast<float>(window),
                             std::max(0, level - p.level_slack), level + p.level_slack)) {
      const int d = hamming(mp->descriptor, f.descriptors[j]);
      if (d < best) best = d, best_j = j;
    }
    if (best_j < 0) continue;
    const msg::KeyPoint& k = f.keypoints[best_j];
    pairs.push_back({bearing(k.x, k.y), c / dist, p.inlier_px * s.scale[k.octave] / cam.fx});
  }
  out.candidates = static_cast<int>(pairs.size());
  if (out.candidates < p.min_inliers) return out;

  HashRng rng(seed);
  const int n = out.candidates;
  int best_count = 0;
  Eigen::Matrix3d best_R = Eigen::Matrix3d::Identity();
  const double max_angle = p.max_angle_deg * M_PI / 180.0;
  for (int it = 0; it < p.iterations; ++it) {
    const int a = rng.below(n), b = rng.below(n);
    // Two bearings a degree apart or less leave the rotation about them loose.
    if (a == b || pairs[a].pred.cross(pairs[b].pred).norm() < 0.02) continue;
    const Eigen::Matrix3d R =
        rotationBetweenBearings({pairs[a].obs, pairs[b].obs}, {pairs[a].pred, pairs[b].pred});
    if (Eigen::AngleAxisd(R).angle() > max_angle) continue;
    const int count = countInliers(pairs, R, nullptr);
    if (count > best_count) best_count = count, best_R = R;
  }
  // Refit on the inliers, twice: the refit may take in pairs the sample's rotation just missed.
  std::vector<uint8_t> in;
  for (int round = 0; round < 2 && best_count >= 2; ++round) {
    countInliers(pairs, best_R, &in);
    std::vector<Eigen::Vector3d> obs, pred;
    for (size_t i = 0; i < pairs.size(); ++i)
      if (in[i]) obs.push_back(pairs[i].obs), pred.push_back(pairs[i].pred);
    best_R = rotationBetweenBearings(obs, pred);
  }
  out.inliers = countInliers(pairs, best_R, nullptr);
  // obs = R * pred is the point's bearing in the camera rotated from the prediction by R^T.
  out.R_pred_c = best_R.transpose();
  out.ok = out.inliers >= p.min_inliers;
  return out;
}

}  // namespace binloop
