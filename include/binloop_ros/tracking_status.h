#pragma once
// What the Tracking nodelet has done and what went wrong, counted in one place: reported in its diagnostics
// and in the statistics service.
#include <diagnostic_updater/diagnostic_updater.h>

#include <cstdint>
#include <string>

#include "binloop/tracking/tracking_stage.h"
#include "binloop_ros/callback_guard.h"

namespace binloop_ros {

struct TrackingStatus {
  uint64_t frames = 0, lost = 0, rejected = 0, keyframes_sent = 0, clock_restarts = 0;
  std::string last_problem;
  double last_latency_ms = 0;

  /// What the nodelet is doing besides the counts above and the stage's, for report().
  struct Now {
    double quiet_s = 0, stale_after_s = 2;  // since the last pair; more is WARN
    size_t waiting = 0;                     // pairs waiting (PairIntake)
    double stamp_diff_s = 0;                // between the last pair's left and right
    double cpu_s = 0;
  };
  /// The diagnostics: the worst of what went wrong as the summary, then every count.
  void report(diagnostic_updater::DiagnosticStatusWrapper& s, const binloop::TrackingStage& stage,
              const Now& now, const CallbackGuard& guard) const;
};

}  // namespace binloop_ros
