#include "binloop_ros/tracking_status.h"

#include "binloop_ros/stage_diagnostics.h"

namespace binloop_ros {

void TrackingStatus::report(diagnostic_updater::DiagnosticStatusWrapper& s,
                            const binloop::TrackingStage& stage, const Now& now,
                            const CallbackGuard& guard) const {
  using diagnostic_msgs::DiagnosticStatus;
  const binloop::KeyframesInFlight& in_flight = stage.inFlight();
  if (!stage.tracker())
    s.summary(DiagnosticStatus::WARN, "waiting for camera_info");
  else if (now.quiet_s > now.stale_after_s)
    s.summary(DiagnosticStatus::WARN,
              "no stereo pair for " + std::to_string(static_cast<int>(now.quiet_s)) + " s");
  else if (guard.failures() > 0)
    s.summary(DiagnosticStatus::WARN, "tracking; a callback failed");
  else if (in_flight.givenUp() > 0)
    s.summary(DiagnosticStatus::WARN, "tracking; local mapping did not answer some keyframes");
  else if (stage.tracker()->state() == binloop::msg::TrackingState::kLost)
    s.summary(DiagnosticStatus::WARN, "lost");
  else if (rejected > 0)
    s.summary(DiagnosticStatus::WARN, "tracking; some input dropped");
  else
    s.summary(DiagnosticStatus::OK, "tracking");
  s.add("frames tracked", frames);
  s.add("frames lost", lost);
  s.add("clock restarts", clock_restarts);
  s.add("maps taken from local mapping", stage.mapsAdopted());
  s.add("seconds since the last pair", now.quiet_s);
  s.add("keyframes sent", keyframes_sent);
  s.add("mapping queue", in_flight.count());
  s.add("keyframes given up (mapping did not answer)", in_flight.givenUp());
  s.add("keyframes sent again (mapping restarted)", stage.keyframesResent());
  s.add("keyframes mapping lost for good", stage.keyframesNotResent());
  s.add("pairs waiting", now.waiting);
  s.add("loop corrections applied", stage.corrections());
  s.add("stereo stamp difference s", now.stamp_diff_s);
  s.add("processing ms (last frame)", last_latency_ms);
  addCommonLines(s, rejected, last_problem, guard, now.cpu_s);
}

}  // namespace binloop_ros
