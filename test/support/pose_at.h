#pragma once
// A camera pose with no rotation at a given position: the shape most hand-made routes and gates need.
#include "binloop/types/pose.h"

namespace binloop::test {

inline Pose3 poseAt(double x, double y, double z) {
  Pose3 T = Pose3::Identity();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

}  // namespace binloop::test
