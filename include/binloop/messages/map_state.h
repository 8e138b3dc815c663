#pragma once
// The parts of the map that travel between stages, as plain values. A stage that receives one copies
// what it needs into its own state; nothing here points into another stage's memory. Every field maps
// onto a ROS message field (ids uint64, poses geometry_msgs/Pose, descriptors uint8[32]).
#include <Eigen/Core>
#include <vector>

#include "binloop/map/ids.h"
#include "binloop/types/binary_descriptor.h"
#include "binloop/types/pose.h"

namespace binloop::msg {

/// A map point as its owner knows it now. The viewing range and direction let a tracker decide whether,
/// and at what scale, the point should be visible in a frame (ORB-SLAM2's isInFrustum).
struct MapPoint {
  MapPointId id = kNoId;
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();
  Desc256 descriptor;                                // the most central of its observations' descriptors
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();  // mean viewing direction (unit), world frame
  float min_distance = 0, max_distance = 0;          // scale-invariance range, metres from a camera
  SlamKeyframeId reference = kNoId;                  // the keyframe it was created in
  uint32_t observations = 0;                         // keyframes that see it
};

/// Carries `p` along when the frame it was placed in moves by `d` (a loop correction, a merge): its
/// position and its viewing direction turn together.
inline void moveRigidly(MapPoint& p, const Pose3& d) {
  p.p_w = d * p.p_w;
  p.normal = (d.linear().cast<float>() * p.normal).normalized();
}

struct CovisibleEdge {
  SlamKeyframeId id = kNoId;
  uint32_t weight = 0;  // map points both keyframes see
};

/// A keyframe's mutable state: what local mapping refines and loop closing corrects.
struct KeyframeState {
  SlamKeyframeId id = kNoId;
  Pose3 T_w_c = Pose3::Identity();
  std::vector<MapPointId> point_ids;     // per keypoint, kNoId where none
  std::vector<CovisibleEdge> covisible;  // weight >= the covisibility threshold, strongest first
  SlamKeyframeId parent = kNoId;         // spanning tree
};

}  // namespace binloop::msg
