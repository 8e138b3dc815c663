#pragma once
// Rigid transforms named by their frames: T_a_b maps coordinates in frame b to frame a
// (p_a = T_a_b * p_b). Poses are always typed Eigen transforms, never cv::Mat.
#include <Eigen/Geometry>
#include <vector>

namespace binloop {

using Pose3 = Eigen::Isometry3d;

/// A pose with its time, e.g. one line of a trajectory file (T_w_c of the left camera).
struct StampedPose {
  double stamp_s = 0.0;
  Pose3 T_w_c = Pose3::Identity();
};

using Trajectory = std::vector<StampedPose>;

}  // namespace binloop
