#include "binloop/pipeline/final_trajectory.h"

#include "binloop/io/trajectory_io.h"

namespace binloop {

Trajectory finalTrajectory(const std::vector<msg::TrackedFrame>& frames,
                           const KeyframePoseFn& keyframe_pose) {
  Trajectory out;
  out.reserve(frames.size());
  for (const msg::TrackedFrame& f : frames) {
    Pose3 T = f.T_w_c, T_ref;
    if (f.state != msg::TrackingState::kLost && f.reference != kNoId && keyframe_pose(f.reference, &T_ref))
      T = T_ref * f.T_ref_c;
    out.push_back({f.stamp_s, T});
  }
  return out;
}

void writeTrajectoryFiles(const std::string& stem, const Trajectory& t) {
  std::vector<Pose3> poses;
  poses.reserve(t.size());
  for (const StampedPose& p : t) poses.push_back(p.T_w_c);
  writeKittiPoses(stem + ".kitti.txt", poses);
  writeTumTrajectory(stem + ".tum.txt", t);
}

}  // namespace binloop
