#pragma once
// A stage nodelet's diagnostics: one status task under hardware id "binloop", published once a second from
// a wall-clock timer on the nodelet's own callback queue (so never beside one of its callbacks), whether
// messages flow or not: a graph waiting for camera_info, or one whose bag has ended with use_sim_time, still
// says what it last saw. Updating from the callbacks instead left the last state unpublished whenever the
// updater's rate limit swallowed the final call.
#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/node_handle.h>

#include <cstdint>
#include <string>

#include "binloop_ros/callback_guard.h"

namespace binloop_ros {

/// The lines every stage adds after its own, under the same names in all four: input it dropped and the
/// last problem it saw, callbacks its guard caught, and the CPU time its callbacks took.
inline void addCommonLines(diagnostic_updater::DiagnosticStatusWrapper& s, uint64_t dropped,
                           const std::string& last_problem, const CallbackGuard& guard, double cpu_s) {
  s.add("input dropped", dropped);
  s.add("last problem", last_problem);
  s.add("callbacks failed", guard.failures());
  s.add("last callback failure", guard.lastFailure());
  s.add("cpu s in callbacks", cpu_s);
}

class StageDiagnostics {
 public:
  StageDiagnostics(ros::NodeHandle& nh, ros::NodeHandle& pnh, const std::string& task,
                   diagnostic_updater::TaskFunction fill)
      : updater_(nh, pnh) {
    updater_.setHardwareID("binloop");
    updater_.add(task, std::move(fill));
    timer_ = nh.createWallTimer(ros::WallDuration(1.0),
                                [this](const ros::WallTimerEvent&) { updater_.force_update(); });
  }
  StageDiagnostics(const StageDiagnostics&) = delete;
  StageDiagnostics& operator=(const StageDiagnostics&) = delete;

 private:
  diagnostic_updater::Updater updater_;
  ros::WallTimer timer_;
};

}  // namespace binloop_ros
