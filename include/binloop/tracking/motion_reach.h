#pragma once
// Where the camera can be when the motion model predicts across lost frames: within
// min_gate + 1/2 a dt^2 of the predicted position. A road whose texture repeats lets a wrong pose gather
// dozens of inliers metres away; this is the check that refuses it, on every tracking path.
#include <Eigen/Core>

#include "binloop/types/pose.h"

namespace binloop {

class MotionReach {
 public:
  /// No prediction: every pose is admitted.
  MotionReach() = default;
  MotionReach(const Eigen::Vector3d& predicted, double min_gate_m, double max_accel_mps2, double dt_s)
      : active_(true),
        predicted_(predicted),
        radius_m_(min_gate_m + 0.5 * max_accel_mps2 * dt_s * dt_s),
        dt_s_(dt_s) {}

  /// Whether the camera could be at T_w_c; a refused pose is remembered (the nearest) for the frame's report.
  bool admits(const Pose3& T_w_c) {
    if (!active_) return true;
    const double off = (T_w_c.translation() - predicted_).norm();
    if (off <= radius_m_) return true;
    if (nearest_refused_m_ < 0 || off < nearest_refused_m_) nearest_refused_m_ = off;
    return false;
  }

  bool active() const { return active_; }
  double radiusM() const { return radius_m_; }
  double dtS() const { return dt_s_; }
  /// Distance of the nearest refused pose from the prediction, or -1 when none was refused.
  double nearestRefusedM() const { return nearest_refused_m_; }

 private:
  bool active_ = false;
  Eigen::Vector3d predicted_ = Eigen::Vector3d::Zero();
  double radius_m_ = 0, dt_s_ = 0;
  double nearest_refused_m_ = -1;
};

}  // namespace binloop
