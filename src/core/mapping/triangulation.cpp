#include "binloop/mapping/triangulation.h"

#include <Eigen/SVD>
#include <cmath>

#include "binloop/map/keypoint_geometry.h"

namespace binloop {

std::optional<Eigen::Vector3d> triangulateLinear(const Pose3& T_c1_w, const Pose3& T_c2_w,
                                                 const Eigen::Vector2d& x1, const Eigen::Vector2d& x2) {
  const Eigen::Matrix<double, 3, 4> P1 = T_c1_w.matrix().topRows<3>();
  const Eigen::Matrix<double, 3, 4> P2 = T_c2_w.matrix().topRows<3>();
  Eigen::Matrix4d A;
  A.row(0) = x1.x() * P1.row(2) - P1.row(0);
  A.row(1) = x1.y() * P1.row(2) - P1.row(1);
  A.row(2) = x2.x() * P2.row(2) - P2.row(0);
  A.row(3) = x2.y() * P2.row(2) - P2.row(1);
  const Eigen::JacobiSVD<Eigen::Matrix4d> svd(A, Eigen::ComputeFullV);
  const Eigen::Vector4d X = svd.matrixV().col(3);
  if (std::abs(X(3)) < 1e-12) return std::nullopt;
  return Eigen::Vector3d(X.head<3>() / X(3));
}

namespace {

Eigen::Vector2d normalised(const StereoCamera& c, const msg::KeyPoint& k) {
  return {(k.x - c.cx) / c.fx, (k.y - c.cy) / c.fy};
}

// The angle the baseline subtends at the stereo point: the parallax a single stereo view already has.
double stereoCos(const StereoCamera& c, const msg::KeyPoint& k) {
  return std::cos(2 * std::atan2(c.baseline_m / 2, static_cast<double>(k.depth)));
}

Eigen::Vector3d unprojectStereo(const TriangulationView& v) {
  const msg::KeyPoint& k = *v.keypoint;
  const Eigen::Vector2d x = normalised(*v.camera, k);
  return *v.T_w_c * Eigen::Vector3d(x.x() * k.depth, x.y() * k.depth, k.depth);
}

}  // namespace

TriangulationResult triangulatePair(const TriangulationView& a, const TriangulationView& b,
                                    const ScalePyramid& s, const TriangulationParams& p,
                                    Eigen::Vector3d* p_w) {
  const msg::KeyPoint &ka = *a.keypoint, &kb = *b.keypoint;
  const Eigen::Vector2d xa = normalised(*a.camera, ka), xb = normalised(*b.camera, kb);
  const Eigen::Vector3d ray_a = a.T_w_c->linear() * xa.homogeneous();
  const Eigen::Vector3d ray_b = b.T_w_c->linear() * xb.homogeneous();
  const double cos_rays = ray_a.dot(ray_b) / (ray_a.norm() * ray_b.norm());
  const bool sa = hasStereo(ka), sb = hasStereo(kb);
  const double cos_sa = sa ? stereoCos(*a.camera, ka) : 2.0, cos_sb = sb ? stereoCos(*b.camera, kb) : 2.0;
  const double cos_stereo = std::min(cos_sa, cos_sb);

  Eigen::Vector3d X;
  if (cos_rays < cos_stereo && cos_rays > 0 && (sa || sb || cos_rays < p.max_ray_cos)) {
    const auto t = triangulateLinear(a.T_w_c->inverse(), b.T_w_c->inverse(), xa, xb);
    if (!t) return TriangulationResult::kParallel;
    X = *t;
  } else if (sa && cos_sa < cos_sb) {
    X = unprojectStereo(a);
  } else if (sb && cos_sb < cos_sa) {
    X = unprojectStereo(b);
  } else {
    return TriangulationResult::kParallel;
  }

  bool front_a = false, front_b = false;
  const double ea = reprojectionChi2(*a.camera, a.T_w_c->inverse(), X, ka, s.inv_sigma2[ka.octave], &front_a);
  const double eb = reprojectionChi2(*b.camera, b.T_w_c->inverse(), X, kb, s.inv_sigma2[kb.octave], &front_b);
  if (!front_a || !front_b) return TriangulationResult::kBehind;
  if (ea > (ka.right_x >= 0 ? p.chi2_stereo : p.chi2_mono) ||
      eb > (kb.right_x >= 0 ? p.chi2_stereo : p.chi2_mono))
    return TriangulationResult::kReprojection;

  // A point seen at a coarser level from farther away: distance ratio and level ratio must agree.
  const double da = (X - a.T_w_c->translation()).norm(), db = (X - b.T_w_c->translation()).norm();
  if (da <= 0 || db <= 0) return TriangulationResult::kScale;
  const double ratio_dist = db / da;
  const double ratio_octave = static_cast<double>(s.scale[ka.octave]) / s.scale[kb.octave];
  const double slack = p.scale_ratio_slack * s.factor;
  if (ratio_dist * slack < ratio_octave || ratio_dist > ratio_octave * slack)
    return TriangulationResult::kScale;
  *p_w = X;
  return TriangulationResult::kOk;
}

}  // namespace binloop
