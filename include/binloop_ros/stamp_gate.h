#pragma once
// Which stereo pairs' time stamps tracking takes. A camera's or a bag's clock runs forward in steps of a
// frame or a few; the field also sends a stamp out of ROS's range, one a million seconds ahead (a bad clock
// sample), a late or repeated pair, and a clock that starts again (a bag played again or looped, simulated
// time reset). One bad stamp must not stop tracking for good, so a stamp is taken when it comes after the
// last taken one by at most `max_jump_s`; any other is dropped with its reason, unless `confirm_pairs`
// pairs in a row agree on the new clock (each after the one before, within `max_jump_s`): then the clock
// really jumped, forward (tracking finds its place again as after missing frames) or back (Restart: the
// clock started again, Tracker::restartClock).
#include <cstdint>
#include <string>

namespace binloop_ros {

struct StampGateParams {
  double max_jump_s = 5;  // ~max_time_jump
  int confirm_pairs = 3;  // ~time_jump_confirm_pairs
};

class StampGate {
 public:
  enum class Verdict { kTake, kJumpedForward, kRestart, kDrop };
  struct Decision {
    Verdict verdict = Verdict::kDrop;
    std::string reason;  // why it was dropped, or what the clock did
    bool taken() const { return verdict != Verdict::kDrop; }
  };

  /// Throws std::invalid_argument for max_jump_s <= 0 or confirm_pairs < 1.
  explicit StampGate(StampGateParams p = {});

  Decision check(double stamp_s);
  /// Forget the clock (a reset or a loaded map): the next stamp is taken whatever it is.
  void reset();
  double last() const { return last_; }

 private:
  StampGateParams p_;
  bool have_ = false;
  double last_ = 0;
  int run_ = 0;          // pairs in a row off the clock that agree with each other
  double run_last_ = 0;  // the last of them
};

}  // namespace binloop_ros
