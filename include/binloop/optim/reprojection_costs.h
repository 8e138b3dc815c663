#pragma once
// Ceres cost functors for reprojection errors in a rectified stereo camera (ORB-SLAM2's g2o edges
// EdgeStereoSE3ProjectXYZ / EdgeSE3ProjectXYZ and their *OnlyPose variants).
//
// Pose parametrisation
// --------------------
// A camera pose T_c_w (world -> camera) is one 6-vector xi = (w, rho) that perturbs a constant anchor pose
// T0_c_w, the pose the solve started from:
//
//     T_c_w(xi) = [Exp(w) | rho] * T0_c_w,   i.e.   p_c = Exp(w) (R0 p_w + t0) + rho,
//     R = Exp(w) R0,   t = Exp(w) t0 + rho,
//
// where w is an angle-axis vector (rad) and rho a translation (m) in the camera frame. This is the same
// left-multiplied increment as g2o's SE3Quat (ORB-SLAM2), except that the expansion point stays T0 for the
// whole solve instead of moving every iteration. Chosen over quaternion + translation because:
//   - the block is Euclidean: no Manifold, and a camera is one 6-wide block in the Schur complement;
//   - xi = 0 is exactly T0: a fixed keyframe, or a pose the data does not move, comes back bit-identical,
//     with no quaternion <-> matrix round trip;
//   - its one singularity, |w| = pi, is far outside any correction a tracked pose or a local window needs.
// The price is that a BA functor carries its keyframe's R0, t0 (12 doubles).
//
// Residuals
// ---------
// With p_c = (x, y, z), the projections are u = fx x/z + cx, v = fy y/z + cy and, in the right image,
// u_r = u - bf/z (bf = fx * baseline). For an observation (u*, v*, u_r*) found at pyramid octave o, with
// inv_sigma2 = 1 / scale_factor^(2 o):
//
//     stereo:  r = sqrt(inv_sigma2) * (u* - u, v* - v, u_r* - u_r)     (3 rows)
//     mono:    r = sqrt(inv_sigma2) * (u* - u, v* - v)                 (2 rows)
//
// so chi2 = |r|^2 = e^T (inv_sigma2 I) e, g2o's chi2 with ORB-SLAM2's information matrix, to compare with
// the 95 % quantiles of chi-square, 7.815 (3 dof) and 5.991 (2 dof). Ceres minimises 1/2 sum rho(|r|^2);
// ceres::HuberLoss(delta) is rho(s) = s for s <= delta^2, 2 delta sqrt(s) - delta^2 above, which is g2o's
// RobustKernelHuber on chi2.
//
// The pose optimiser's Jacobians are automatic (ceres::AutoDiffCostFunction, dual numbers): exact to
// rounding and short to check; the rotation is ceres::AngleAxisRotatePoint, whose derivative is exact at
// w = 0 too. Bundle adjustment uses linearizeReprojection below, the same residual with its Jacobians in
// closed form (a test holds them to the automatic ones): its solver is our own (schur_lm), and the dual
// numbers cost it as much as the whole linear algebra.
//
// A point at z <= 0 (behind the camera or on its plane) makes the functor return false, so Ceres rejects
// any step that would put an observed point there. Callers must not add an observation whose point is
// already behind the camera at the start (Ceres then fails the initial evaluation); the optimisers flag
// those as outliers first.
#include <ceres/autodiff_cost_function.h>
#include <ceres/rotation.h>

#include <Eigen/Core>
#include <cmath>

#include "binloop/types/pose.h"
#include "binloop/types/stereo_camera.h"

namespace binloop {

/// The camera constants a residual needs.
struct ProjectionConstants {
  double fx = 0, fy = 0, cx = 0, cy = 0, bf = 0;
  ProjectionConstants() = default;
  explicit ProjectionConstants(const StereoCamera& c) : fx(c.fx), fy(c.fy), cx(c.cx), cy(c.cy), bf(c.bf()) {}
};

/// p_c = Exp(w) p0 + rho, with xi = (w, rho) (see the top of this file); p0 = T0 * p_w.
template <typename T>
inline void applyPoseIncrement(const T* xi, const T* p0, T* p_c) {
  ceres::AngleAxisRotatePoint(xi, p0, p_c);
  p_c[0] += xi[3];
  p_c[1] += xi[4];
  p_c[2] += xi[5];
}

/// T_c_w(xi) = [Exp(w) | rho] * T0_c_w in double, the pose a solution xi stands for. xi = 0 gives T0
/// bit-identical.
Pose3 poseFromIncrement(const double* xi, const Pose3& T0_c_w);

/// Writes the kDim whitened residuals of a camera-frame point; false when z <= 0 (or z is NaN). The
/// residuals are written in any case, for a caller that wants them (they are not finite at z = 0).
template <int kDim, typename T>
inline bool whitenedReprojection(const ProjectionConstants& k, const double* obs, double sqrt_info,
                                 const T* p_c, T* r) {
  static_assert(kDim == 2 || kDim == 3, "2 rows (mono) or 3 rows (stereo)");
  const T inv_z = T(1.0) / p_c[2];
  const T u = k.fx * p_c[0] * inv_z + k.cx;
  r[0] = sqrt_info * (obs[0] - u);
  r[1] = sqrt_info * (obs[1] - (k.fy * p_c[1] * inv_z + k.cy));
  if constexpr (kDim == 3) r[2] = sqrt_info * (obs[2] - (u - k.bf * inv_z));
  return p_c[2] > T(0.0);
}

/// One observation of a point by a keyframe, both variables (bundle adjustment). Parameter blocks: the
/// keyframe's xi (6) about its anchor T0_c_w, then p_w (3). kDim = 3: stereo (u, v, u_right); 2: mono.
template <int kDim>
class ReprojectionCost {
 public:
  ReprojectionCost(const ProjectionConstants& k, const Pose3& T0_c_w, const Eigen::Vector2d& uv,
                   double u_right, double inv_sigma2)
      : k_(k),
        R0_(T0_c_w.linear()),
        t0_(T0_c_w.translation()),
        obs_{uv.x(), uv.y(), u_right},
        sqrt_info_(std::sqrt(inv_sigma2)) {}

  template <typename T>
  bool operator()(const T* xi, const T* p_w, T* r) const {
    T p0[3];
    for (int i = 0; i < 3; ++i) p0[i] = R0_(i, 0) * p_w[0] + R0_(i, 1) * p_w[1] + R0_(i, 2) * p_w[2] + t0_[i];
    T p_c[3];
    applyPoseIncrement(xi, p0, p_c);
    return whitenedReprojection<kDim>(k_, obs_, sqrt_info_, p_c, r);
  }

  /// chi2 = |r|^2 at (xi, p_w) in double; `in_front` tells whether z > 0 there.
  double chi2(const double* xi, const double* p_w, bool* in_front) const {
    double r[kDim];
    *in_front = (*this)(xi, p_w, r);
    double s = 0;
    for (int i = 0; i < kDim; ++i) s += r[i] * r[i];
    return s;
  }

  using CostFunction = ceres::AutoDiffCostFunction<ReprojectionCost, kDim, 6, 3>;
  /// The Ceres cost function (the caller, or the ceres::Problem, owns it); functor() reaches chi2().
  static CostFunction* create(const ProjectionConstants& k, const Pose3& T0_c_w, const Eigen::Vector2d& uv,
                              double u_right, double inv_sigma2) {
    return new CostFunction(new ReprojectionCost(k, T0_c_w, uv, u_right, inv_sigma2));
  }

 private:
  ProjectionConstants k_;
  Eigen::Matrix3d R0_;
  Eigen::Vector3d t0_;
  double obs_[3];
  double sqrt_info_;
};

/// The same residual with the point held fixed (pose-only optimisation): one parameter block, the
/// camera's xi (6) about T0_c_w. T0 * p_w is computed once, here.
template <int kDim>
class PoseOnlyReprojectionCost {
 public:
  PoseOnlyReprojectionCost(const ProjectionConstants& k, const Pose3& T0_c_w, const Eigen::Vector3d& p_w,
                           const Eigen::Vector2d& uv, double u_right, double inv_sigma2)
      : k_(k), obs_{uv.x(), uv.y(), u_right}, sqrt_info_(std::sqrt(inv_sigma2)) {
    const Eigen::Vector3d p0 = T0_c_w * p_w;
    p0_[0] = p0.x();
    p0_[1] = p0.y();
    p0_[2] = p0.z();
  }

  template <typename T>
  bool operator()(const T* xi, T* r) const {
    const T p0[3] = {T(p0_[0]), T(p0_[1]), T(p0_[2])};
    T p_c[3];
    applyPoseIncrement(xi, p0, p_c);
    return whitenedReprojection<kDim>(k_, obs_, sqrt_info_, p_c, r);
  }

  /// chi2 = |r|^2 at xi in double; `in_front` tells whether z > 0 there.
  double chi2(const double* xi, bool* in_front) const {
    double r[kDim];
    *in_front = (*this)(xi, r);
    double s = 0;
    for (int i = 0; i < kDim; ++i) s += r[i] * r[i];
    return s;
  }

  using CostFunction = ceres::AutoDiffCostFunction<PoseOnlyReprojectionCost, kDim, 6>;
  static CostFunction* create(const ProjectionConstants& k, const Pose3& T0_c_w, const Eigen::Vector3d& p_w,
                              const Eigen::Vector2d& uv, double u_right, double inv_sigma2) {
    return new CostFunction(new PoseOnlyReprojectionCost(k, T0_c_w, p_w, uv, u_right, inv_sigma2));
  }

 private:
  ProjectionConstants k_;
  double p0_[3];
  double obs_[3];
  double sqrt_info_;
};

/// One observation linearised: the whitened residual of ReprojectionCost and its Jacobians at xi = 0.
/// Always three rows; a mono observation's third row is zero, so a solver can use one block size.
struct LinearizedReprojection {
  Eigen::Vector3d r = Eigen::Vector3d::Zero();
  Eigen::Matrix<double, 3, 6> J_pose = Eigen::Matrix<double, 3, 6>::Zero();  // by xi = (w, rho)
  Eigen::Matrix3d J_point = Eigen::Matrix3d::Zero();                         // by p_w
  double chi2 = 0;                                                           // |r|^2
  bool in_front = false;                                                     // z > 0
};

/// ReprojectionCost<3> (stereo) or <2> (mono)'s residual with its Jacobians in closed form, at xi = 0
/// about the pose T_c_w = [R | t] (the bundle adjuster moves its expansion point every iteration, as g2o
/// does, so it needs them only there). The residual is whitenedReprojection's. With p_c = R p_w + t = (x, y,
/// z):
///     d p_c / d w = -[p_c]x,   d p_c / d rho = I,   d p_c / d p_w = R,
///     d (u, v, u_r) / d p_c = [fx/z, 0, -fx x/z^2;  0, fy/z, -fy y/z^2;  fx/z, 0, (bf - fx x)/z^2],
/// and the residual is the observation minus the projection, hence the minus sign. The Jacobians are left
/// unset (zero) behind the camera, where the residual means nothing.
inline LinearizedReprojection linearizeReprojection(const ProjectionConstants& k, const Pose3& T_c_w,
                                                    const Eigen::Vector3d& p_w, const double* obs,
                                                    double sqrt_info, bool stereo,
                                                    bool with_jacobians = true) {
  LinearizedReprojection l;
  const Eigen::Matrix3d R = T_c_w.linear();
  const Eigen::Vector3d p_c = R * p_w + T_c_w.translation();
  l.in_front = stereo ? whitenedReprojection<3, double>(k, obs, sqrt_info, p_c.data(), l.r.data())
                      : whitenedReprojection<2, double>(k, obs, sqrt_info, p_c.data(), l.r.data());
  l.chi2 = l.r.squaredNorm();
  if (!with_jacobians || !l.in_front) return l;
  const double inv_z = 1.0 / p_c.z(), inv_z2 = inv_z * inv_z;
  Eigen::Matrix3d d_proj = Eigen::Matrix3d::Zero();  // minus sqrt_info times d (u, v, u_r) / d p_c
  d_proj(0, 0) = -sqrt_info * k.fx * inv_z;
  d_proj(0, 2) = sqrt_info * k.fx * p_c.x() * inv_z2;
  d_proj(1, 1) = -sqrt_info * k.fy * inv_z;
  d_proj(1, 2) = sqrt_info * k.fy * p_c.y() * inv_z2;
  if (stereo) {
    d_proj(2, 0) = d_proj(0, 0);
    d_proj(2, 2) = -sqrt_info * (k.bf - k.fx * p_c.x()) * inv_z2;
  }
  l.J_pose.leftCols<3>() = -d_proj * skew(p_c);
  l.J_pose.rightCols<3>() = d_proj;
  l.J_point = d_proj * R;
  return l;
}

using StereoReprojectionCost = ReprojectionCost<3>;
using MonoReprojectionCost = ReprojectionCost<2>;
using StereoPoseOnlyCost = PoseOnlyReprojectionCost<3>;
using MonoPoseOnlyCost = PoseOnlyReprojectionCost<2>;

}  // namespace binloop
