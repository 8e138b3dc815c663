#pragma once
// Tracking's flow control towards local mapping: how many keyframes it sent that mapping has not answered
// yet (Tracker::track makes fewer keyframes while some are in flight). Flow control must heal itself: a
// keyframe mapping never answers (mapping restarting, a full TCP queue in the split launch, its process gone)
// would hold the count up for good, and at the limit no keyframe would be made again.
#include <cstdint>
#include <string>

namespace binloop {

class KeyframesInFlight {
 public:
  /// Keyframes are given up after `timeout_s` without any answer from mapping.
  explicit KeyframesInFlight(double timeout_s = 5) : timeout_s_(timeout_s) {}

  /// A keyframe was sent at `now_s` (any clock that only goes forward, the same for every call).
  void sent(double now_s) {
    ++count_;
    last_contact_s_ = now_s;
  }
  /// Mapping answered one keyframe at `now_s` (a map update that is not a loop correction).
  void answered(double now_s) {
    if (count_ > 0) --count_;
    last_contact_s_ = now_s;
  }
  /// Mapping was heard from at `now_s` without answering a keyframe (a correction).
  void heard(double now_s) { last_contact_s_ = now_s; }
  /// A new tracker: nothing it sent is in flight.
  void clear() { count_ = 0; }

  /// At `now_s`, before a frame is tracked: gives up the keyframes in flight when no mapping listens
  /// (`mapping_listens` false: waiting would stop keyframes and the local map would run out) or mapping has
  /// answered nothing for longer than the timeout. Returns why they were given up, or "" when they are kept.
  std::string giveUpIfStale(double now_s, bool mapping_listens);

  int count() const { return count_; }
  /// Keyframes given up since construction.
  uint64_t givenUp() const { return given_up_; }

 private:
  double timeout_s_;
  int count_ = 0;
  double last_contact_s_ = 0;
  uint64_t given_up_ = 0;
};

}  // namespace binloop
