#pragma once
// Each nodelet's diagnostics go out once a second from a wall-clock timer on the nodelet's own callback queue
// (so never beside one of its callbacks), whether messages flow or not: a graph waiting for camera_info, or
// one whose bag has ended with use_sim_time, still says what it last saw. Updating from the callbacks instead
// left the last state unpublished whenever the updater's rate limit swallowed the final call.
#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/node_handle.h>

namespace binloop_ros {

inline ros::WallTimer publishDiagnosticsEverySecond(ros::NodeHandle& nh, diagnostic_updater::Updater& u) {
  return nh.createWallTimer(ros::WallDuration(1.0), [&u](const ros::WallTimerEvent&) { u.force_update(); });
}

}  // namespace binloop_ros
