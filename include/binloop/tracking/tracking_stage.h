#pragma once
// The tracking stage of a graph around its one Tracker, without ROS: the tracker is made once the camera is
// known (from parameters, or the first camera_info); a map local mapping sends a restarted tracking is
// adopted, or kept until the camera is known; a loaded map or a reset replaces the tracker; keyframes sent to
// mapping are counted until answered (KeyframesInFlight), and loop corrections applied are counted.
// Not thread-safe: one caller (the nodelet's callbacks run one at a time for it).
#include <cstdint>
#include <memory>
#include <optional>

#include "binloop/messages/local_map_update.h"
#include "binloop/tracking/keyframes_in_flight.h"
#include "binloop/tracking/tracker.h"

namespace binloop {

class TrackingStage {
 public:
  /// `camera`: a fixed camera (the tracker is made now; throws for a bad one), or none until setCamera().
  TrackingStage(TrackerParams params, std::optional<StereoCamera> camera, double keyframe_timeout_s);

  Tracker* tracker() { return tracker_.get(); }
  const Tracker* tracker() const { return tracker_.get(); }
  /// A new tracker with this stage's settings (for a map to be loaded into it).
  std::unique_ptr<Tracker> freshTracker(const StereoCamera& camera) const;

  /// The camera is known: the tracker is made (throws as Tracker's constructor) and takes a map kept for it.
  void setCamera(const StereoCamera& camera);

  enum class Adopted { kKept, kIgnored, kTaken, kTakenAfterStartOver };
  /// Local mapping's whole map: kept while there is no tracker; taken by a tracker that gives way to it
  /// (Tracker::givesWayTo), replaced first by a fresh one when it had started (kTakenAfterStartOver: what the
  /// caller keeps of the old tracker's frames must go too).
  Adopted adopt(msg::LocalMapUpdatePtr whole);
  /// A loaded map's tracker, or (null) none until the camera is known; nothing is in flight, no map kept.
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

 private:
  TrackerParams params_;
  std::optional<StereoCamera> fixed_camera_;
  std::unique_ptr<Tracker> tracker_;
  msg::LocalMapUpdatePtr kept_;  // local mapping's map, until the camera is known
  KeyframesInFlight in_flight_;
  uint64_t corrections_ = 0, maps_adopted_ = 0;
};

}  // namespace binloop
