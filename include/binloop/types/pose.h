#pragma once
// Rigid transforms named by their frames: T_a_b maps coordinates in frame b to frame a
// (p_a = T_a_b * p_b). Poses are always typed Eigen transforms, never cv::Mat.
#include <Eigen/Geometry>
#include <cmath>
#include <vector>

namespace binloop {

using Pose3 = Eigen::Isometry3d;
/// A pose's covariance: [x y z rx ry rz].
using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// The same pose with its rotation made exactly orthonormal again. Products of many poses (a motion model
/// applied frame after frame) drift from a rotation by rounding; optimisers check for it.
inline Pose3 orthonormalized(const Pose3& T) {
  Pose3 o = Pose3::Identity();
  o.linear() = Eigen::Quaterniond(T.linear()).normalized().toRotationMatrix();
  o.translation() = T.translation();
  return o;
}

/// The cross-product matrix: skew(v) * w = v x w.
inline Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

/// The angle of a rotation, in degrees (0 to 180).
inline double rotationDeg(const Eigen::Matrix3d& R) { return Eigen::AngleAxisd(R).angle() * 180.0 / M_PI; }

/// A pose with its time, e.g. one line of a trajectory file (T_w_c of the left camera).
struct StampedPose {
  double stamp_s = 0.0;
  Pose3 T_w_c = Pose3::Identity();
};

using Trajectory = std::vector<StampedPose>;

}  // namespace binloop
