#pragma once
// Camera pose from 3-D points and their pixels when no prediction is at hand (relocalisation): RANSAC over
// minimal samples of 4 correspondences solved by OpenCV's AP3P, then the pose refined on the inliers.
// The samples are drawn from HashRng with the caller's seed, so a run repeats exactly.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "binloop/types/pose.h"
#include "binloop/types/stereo_camera.h"

namespace binloop {

struct PnpRansacParams {
  int iterations = 300;
  double chi2 = 5.991;  // an inlier's squared pixel error times its inv_sigma2 (chi-square 95 %, 2 dof)
  int min_inliers = 10;
  double stop_ratio = 0.9;  // stop early once this share of the correspondences are inliers
};

struct PnpRansacResult {
  bool ok = false;
  Pose3 T_c_w = Pose3::Identity();
  std::vector<uint8_t> inlier;
  int inliers = 0;
  int iterations = 0;
};

/// `inv_sigma2` per correspondence (1 / scale^(2 octave)); an empty vector means 1 for all. Throws
/// std::invalid_argument for vectors of different sizes.
PnpRansacResult solvePnpRansac(const std::vector<Eigen::Vector3d>& p_w,
                               const std::vector<Eigen::Vector2d>& uv, const std::vector<double>& inv_sigma2,
                               const StereoCamera& cam, const PnpRansacParams& params, uint64_t seed);

}  // namespace binloop
