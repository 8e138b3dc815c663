#include "binloop_ros/stamp_gate.h"

#include <cmath>
#include <stdexcept>

namespace binloop_ros {

namespace {

std::string seconds(double s) { return std::to_string(s) + " s"; }

}  // namespace

StampGate::StampGate(StampGateParams p) : p_(p) {
  if (!(p_.max_jump_s > 0)) throw std::invalid_argument("~max_time_jump must be > 0 s");
  if (p_.confirm_pairs < 1) throw std::invalid_argument("~time_jump_confirm_pairs must be >= 1");
}

void StampGate::reset() {
  have_ = false;
  run_ = 0;
}

StampGate::Decision StampGate::check(double t) {
  Decision d;
  // ros::Time holds up to 2^32 - 1 s; a stamp beyond (or NaN, or 0: "no stamp") cannot be published again.
  if (!std::isfinite(t) || t <= 0 || t >= 4294967295.0) {
    d.reason = "stamp " + seconds(t) + " is outside ROS's time range (0, 2^32) s";
    return d;
  }
  if (!have_ || (t > last_ && t - last_ <= p_.max_jump_s)) {
    have_ = true;
    last_ = t;
    run_ = 0;
    d.verdict = Verdict::kTake;
    return d;
  }
  // Off the clock: the start or the continuation of a run that may be a new clock.
  if (run_ > 0 && t > run_last_ && t - run_last_ <= p_.max_jump_s)
    ++run_;
  else
    run_ = 1;
  run_last_ = t;
  const bool back = t <= last_;
  if (run_ >= p_.confirm_pairs) {
    d.verdict = back ? Verdict::kRestart : Verdict::kJumpedForward;
    d.reason = std::string("the clock ") + (back ? "went back" : "jumped forward") + " from " +
               seconds(last_) + " to " + seconds(t) + " (" + std::to_string(run_) + " pairs in a row agree)";
    last_ = t;
    run_ = 0;
    return d;
  }
  if (t == last_)
    d.reason = "stamp " + seconds(t) + " repeats the previous pair's";
  else if (back)
    d.reason = "stamp " + seconds(t) + " comes before the previous pair's " + seconds(last_) +
               " (late, or the clock started again)";
  else
    d.reason = "stamp " + seconds(t) + " is " + seconds(t - last_) +
               " after the previous pair's (more than ~max_time_jump, " + seconds(p_.max_jump_s) + ")";
  return d;
}

}  // namespace binloop_ros
