#pragma once
// A rectified stereo pair: both cameras share the intrinsics and the right one sits `baseline_m`
// along +x of the left one (KITTI camera 0 / camera 1).
#include <Eigen/Core>
#include <string>

namespace binloop {

struct StereoCamera {
  double fx = 0, fy = 0, cx = 0, cy = 0;
  double baseline_m = 0;  // distance between optical centres
  int width = 0, height = 0;

  /// fx·b: disparity (px) times depth (m).
  double bf() const { return fx * baseline_m; }
  /// Where a left-camera point appears in the left image, level-0 pixels (p.z() != 0; behind the camera,
  /// p.z() < 0, the formal projection, as of an epipole).
  Eigen::Vector2d project(const Eigen::Vector3d& p) const {
    return {fx * p.x() / p.z() + cx, fy * p.y() / p.z() + cy};
  }
  /// 3x4 projection matrix of the left (right=false) or right camera, as in KITTI calib.txt.
  Eigen::Matrix<double, 3, 4> projectionMatrix(bool right) const;
  /// One line per value, for start-up logs.
  std::string describe() const;

  bool operator==(const StereoCamera& o) const;
};

/// KITTI 00–02 rectified camera 0/1 (fx=718.856, baseline 0.537 m, 1241x376).
StereoCamera kitti00Camera();
/// The camera of a KITTI odometry route, "kitti00" to "kitti12": 00–02 share one calibration, 03 has its
/// own, 04–12 share 04's. Throws std::invalid_argument.
StereoCamera kittiCameraByName(const std::string& name);

}  // namespace binloop
