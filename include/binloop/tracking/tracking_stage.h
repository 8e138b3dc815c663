#pragma once
// The tracking stage of a graph around its one Tracker, without ROS: the tracker is made once the camera is
// known (from parameters, or the first camera_info); a map local mapping sends a restarted tracking is
// adopted, or kept until the camera is known; a loaded map or a reset replaces the tracker; keyframes sent to
// mapping are counted until answered (KeyframesInFlight), and loop corrections applied are counted. The last
// keyframes sent are kept, so that a local mapping restarted from an older state (an autosave) gets the ones
// it lacks again.
// Not thread-safe: one caller (the nodelet's callbacks run one at a time for it).
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <vector>

#include "binloop/messages/keyframe.h"
#include "binloop/messages/local_map_update.h"
#include "binloop/tracking/keyframes_in_flight.h"
#include "binloop/tracking/tracker.h"

namespace binloop {

class TrackingStage {
 public:
  /// `camera`: a fixed camera (the tracker is made now; throws for a bad one), or none until setCamera().
  /// How many of the last keyframes sent are kept to be sent again, by default (about 100 KB each).
  static constexpr size_t kResendWindow = 300;
  TrackingStage(TrackerParams params, std::optional<StereoCamera> camera, double keyframe_timeout_s,
                size_t resend_window = kResendWindow);

  Tracker* tracker() { return tracker_.get(); }
  const Tracker* tracker() const { return tracker_.get(); }
  /// A new tracker with this stage's settings (for a map to be loaded into it).
  std::unique_ptr<Tracker> freshTracker(const StereoCamera& camera) const;

  /// The camera is known: the tracker is made (throws as Tracker's constructor) and takes a map kept for it.
  void setCamera(const StereoCamera& camera);

  enum class Adopted { kKept, kIgnored, kTaken, kTakenAfterStartOver, kBehind };
  /// Local mapping's whole map: kept while there is no tracker; taken by a tracker that gives way to it
  /// (Tracker::givesWayTo), replaced first by a fresh one when it had started (kTakenAfterStartOver: what the
  /// caller keeps of the old tracker's frames must go too). kBehind: a running tracker ignores it, but the
  /// map lacks keyframes this tracker sent (local mapping restarted from an autosave): takeResend() has them.
  Adopted adopt(msg::LocalMapUpdatePtr whole);
  /// After adopt() said kBehind: the kept keyframes the map lacks, oldest first, taken out at `now_s` (not
  /// counted in flight). `missing` (if given) is set to how many it lacks that are no longer kept.
  std::vector<msg::KeyFramePtr> takeResend(double now_s, uint64_t* missing = nullptr);
  bool resendPending() const { return !resend_.empty(); }
  /// A loaded map's tracker, or (null) none until the camera is known; nothing is in flight, no map kept.
  /// Its ids go on in a new session after every id this stage's trackers issued (Tracker::
  /// continueIdsInNewSession): local mapping may still hold the old keyframes, or have them on the way.
  void startOver(std::unique_ptr<Tracker> tracker);
  /// A reset: a fresh tracker when the camera is fixed, else none until the camera is known.
  void reset();

  /// Tracks a frame at `now_s` (a clock that only goes forward); a keyframe it makes is counted in flight.
  Tracker::Output track(const StereoFrame& frame, double now_s);
  /// Local mapping's update at `now_s` (not a whole map: adopt() that): applied, and counted as the answer to
  /// a keyframe or a correction.
  void apply(const msg::LocalMapUpdate& update, double now_s);

  KeyframesInFlight& inFlight() { return in_flight_; }
  const KeyframesInFlight& inFlight() const { return in_flight_; }
  uint64_t corrections() const { return corrections_; }
  uint64_t mapsAdopted() const { return maps_adopted_; }
  /// Keyframes sent again to a restarted local mapping, and those it lacked that were no longer kept.
  uint64_t keyframesResent() const { return resent_; }
  uint64_t keyframesNotResent() const { return not_resent_; }

 private:
  /// Makes `t` the tracker, continuing the ids of those before it (none: until the camera is known).
  void replaceTracker(std::unique_ptr<Tracker> t);
  /// Whether the map lacks keyframes kept in sent_; fills resend_.
  bool behind(const msg::LocalMapUpdate& whole);
  TrackerParams params_;
  std::optional<StereoCamera> fixed_camera_;
  std::unique_ptr<Tracker> tracker_;
  msg::LocalMapUpdatePtr kept_;  // local mapping's map, until the camera is known
  size_t resend_window_;
  std::deque<msg::KeyFramePtr> sent_;  // the last resend_window_ keyframes sent, oldest first
  std::vector<msg::KeyFramePtr> resend_;
  uint64_t resend_missing_ = 0;
  KeyframesInFlight in_flight_;
  uint64_t corrections_ = 0, maps_adopted_ = 0, resent_ = 0, not_resent_ = 0;
  uint64_t keyframe_ids_ = 0, point_ids_ = 0;  // the most any tracker of this stage issued
};

}  // namespace binloop
