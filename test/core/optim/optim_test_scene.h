#pragma once
// Synthetic measurements for the optim tests: the KITTI 00 camera, ORB-SLAM2's pyramid (scale 1.2,
// 8 octaves, sigma = 1.2^octave px), Gaussian pixel noise, and gross outliers (wrong associations).
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "binloop/types/pose.h"
#include "binloop/types/stereo_camera.h"
#include "binloop/util/hash_random.h"

namespace binloop::test {

constexpr double kPi = 3.14159265358979323846;
constexpr double kScaleFactor = 1.2;
constexpr int kOctaves = 8;

inline StereoCamera kitti() { return kittiCameraByName("kitti00"); }

/// ORB-SLAM2's close/far split: stereo measurements only closer than 35 baselines (~19 m).
inline double maxStereoDepth(const StereoCamera& cam) { return 35 * cam.baseline_m; }

inline Eigen::Vector3d randomUnit(HashRng& rng) {
  Eigen::Vector3d v(rng.normal(), rng.normal(), rng.normal());
  return v.normalized();
}

/// T_c_w turned `deg` about a random axis and its camera centre moved `m` in a random direction.
inline Pose3 perturb(const Pose3& T_c_w, double deg, double m, HashRng& rng) {
  Pose3 T_w_c = T_c_w.inverse();
  T_w_c.linear() = (Eigen::AngleAxisd(deg * kPi / 180, randomUnit(rng)) * T_w_c.linear()).eval();
  T_w_c.translation() += m * randomUnit(rng);
  return T_w_c.inverse();
}

inline double rotationErrorDeg(const Pose3& a, const Pose3& b) {
  return rotationDeg(a.linear() * b.linear().transpose());
}

/// Distance between the camera centres of two T_c_w.
inline double centreError(const Pose3& a, const Pose3& b) {
  return (a.inverse().translation() - b.inverse().translation()).norm();
}

/// A keypoint with its ORB-SLAM2 weight; u_right < 0 for monocular.
struct Measurement {
  bool visible = false;
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();
  double u_right = -1;
  double inv_sigma2 = 1;
  double sigma = 1;  // px, of this octave
};

/// Measures a camera-frame point: random octave, noise `pixel_sigma` * 1.2^octave, stereo when closer than
/// maxStereoDepth (and `stereo` allowed). Not visible when z < 0.5 m or the true pixel is off the image.
inline Measurement measure(const StereoCamera& cam, const Eigen::Vector3d& p_c, double pixel_sigma,
                           bool stereo, HashRng& rng) {
  Measurement m;
  if (p_c.z() < 0.5) return m;
  const double u = cam.fx * p_c.x() / p_c.z() + cam.cx, v = cam.fy * p_c.y() / p_c.z() + cam.cy;
  if (u < 0 || u >= cam.width || v < 0 || v >= cam.height) return m;
  m.visible = true;
  const int octave = rng.below(kOctaves);
  m.sigma = std::pow(kScaleFactor, octave);
  m.inv_sigma2 = 1 / (m.sigma * m.sigma);
  m.uv = Eigen::Vector2d(u + pixel_sigma * m.sigma * rng.normal(), v + pixel_sigma * m.sigma * rng.normal());
  const double ur = u - cam.bf() / p_c.z();
  if (stereo && p_c.z() < maxStereoDepth(cam) && ur >= 0)
    m.u_right = ur + pixel_sigma * m.sigma * rng.normal();
  return m;
}

/// A wrong association: the keypoint moves 20-60 sigma in a random image direction (the right-image u
/// with it, so its disparity still looks plausible).
inline void corrupt(Measurement& m, HashRng& rng) {
  const double angle = rng.uniform(0, 2 * kPi), r = rng.uniform(20, 60) * m.sigma;
  const Eigen::Vector2d d(r * std::cos(angle), r * std::sin(angle));
  m.uv += d;
  if (m.u_right >= 0) m.u_right = std::max(0.0, m.u_right + d.x());
}

/// A point seen at pixel (u, v) and depth z by camera T_c_w, in the world frame.
inline Eigen::Vector3d backProject(const StereoCamera& cam, const Pose3& T_c_w, double u, double v,
                                   double z) {
  const Eigen::Vector3d p_c((u - cam.cx) / cam.fx * z, (v - cam.cy) / cam.fy * z, z);
  return T_c_w.inverse() * p_c;
}

}  // namespace binloop::test
