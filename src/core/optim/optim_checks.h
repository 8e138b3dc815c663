#pragma once
// Input checks and the outlier rule shared by the optimisers (private to src/core/optim). Every failure is a
// std::invalid_argument naming the function, the item and the value.
#include <Eigen/Core>
#include <cmath>
#include <stdexcept>
#include <string>

#include "binloop/types/pose.h"
#include "binloop/types/stereo_camera.h"

namespace binloop::optim_detail {

[[noreturn]] inline void fail(const char* who, const std::string& what) {
  throw std::invalid_argument(std::string(who) + ": " + what);
}

inline std::string num(double v) { return std::to_string(v); }

/// fx, fy > 0 and finite, cx, cy finite; bf > 0 when some observation is stereo.
inline void checkCamera(const char* who, const StereoCamera& c, bool needs_stereo) {
  if (!(c.fx > 0) || !std::isfinite(c.fx) || !(c.fy > 0) || !std::isfinite(c.fy))
    fail(who,
         "camera focal lengths must be positive and finite (fx=" + num(c.fx) + ", fy=" + num(c.fy) + ")");
  if (!std::isfinite(c.cx) || !std::isfinite(c.cy))
    fail(who, "camera principal point is not finite (cx=" + num(c.cx) + ", cy=" + num(c.cy) + ")");
  if (needs_stereo && (!(c.bf() > 0) || !std::isfinite(c.bf())))
    fail(who, "stereo observations need a positive baseline (baseline_m=" + num(c.baseline_m) + ")");
}

/// Finite, and a rotation: |R^T R - I| <= 1e-6 elementwise and det R > 0.
inline void checkPose(const char* who, const Pose3& T, const std::string& name) {
  if (!T.matrix().allFinite()) fail(who, name + " is not finite");
  const Eigen::Matrix3d R = T.linear();
  const double err = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (err > 1e-6 || !(R.determinant() > 0))
    fail(who, name + " has no rotation matrix (|R^T R - I| = " + num(err) +
                  ", det = " + num(R.determinant()) + ")");
}

/// Finite point and pixel, finite u_right (negative = monocular), inv_sigma2 > 0 and finite.
inline void checkObservation(const char* who, const std::string& name, const Eigen::Vector3d* p_w,
                             const Eigen::Vector2d& uv, double u_right, double inv_sigma2) {
  if (p_w && !p_w->allFinite()) fail(who, name + ": point p_w is not finite");
  if (!uv.allFinite()) fail(who, name + ": pixel uv is not finite");
  if (!std::isfinite(u_right))
    fail(who, name + ": u_right is not finite (use a negative value for monocular)");
  if (!(inv_sigma2 > 0) || !std::isfinite(inv_sigma2))
    fail(who, name + ": inv_sigma2 must be positive and finite (got " + num(inv_sigma2) + ")");
}

inline void checkPositive(const char* who, const char* name, double v) {
  if (!(v > 0) || !std::isfinite(v))
    fail(who, std::string("parameter ") + name + " must be positive (got " + num(v) + ")");
}

/// Every optimiser's outlier rule: behind the camera, or chi2 above the threshold (or not a number).
inline bool isOutlier(bool in_front, double chi2, double chi2_max) {
  return !in_front || !(chi2 <= chi2_max);
}

}  // namespace binloop::optim_detail
