#include "binloop/tracking/tracking_stage.h"

#include <utility>

namespace binloop {

TrackingStage::TrackingStage(TrackerParams params, std::optional<StereoCamera> camera,
                             double keyframe_timeout_s)
    : params_(std::move(params)), fixed_camera_(std::move(camera)), in_flight_(keyframe_timeout_s) {
  if (fixed_camera_) tracker_ = freshTracker(*fixed_camera_);
}

std::unique_ptr<Tracker> TrackingStage::freshTracker(const StereoCamera& camera) const {
  return std::make_unique<Tracker>(camera, params_);
}

void TrackingStage::setCamera(const StereoCamera& camera) {
  tracker_ = freshTracker(camera);
  if (kept_) adopt(std::exchange(kept_, nullptr));
}

TrackingStage::Adopted TrackingStage::adopt(msg::LocalMapUpdatePtr whole) {
  if (!tracker_) {
    kept_ = std::move(whole);
    return Adopted::kKept;
  }
  if (!tracker_->givesWayTo(*whole)) return Adopted::kIgnored;
  const bool started = tracker_->state() != msg::TrackingState::kNotInitialized;
  if (started) startOver(freshTracker(tracker_->camera()));
  tracker_->adoptMap(*whole);
  ++maps_adopted_;
  return started ? Adopted::kTakenAfterStartOver : Adopted::kTaken;
}

void TrackingStage::startOver(std::unique_ptr<Tracker> tracker) {
  kept_.reset();
  tracker_ = std::move(tracker);
  in_flight_.clear();
}

void TrackingStage::reset() { startOver(fixed_camera_ ? freshTracker(*fixed_camera_) : nullptr); }

Tracker::Output TrackingStage::track(const StereoFrame& frame, double now_s) {
  Tracker::Output out = tracker_->track(frame, in_flight_.count());
  if (out.keyframe) in_flight_.sent(now_s);
  return out;
}

void TrackingStage::apply(const msg::LocalMapUpdate& update, double now_s) {
  if (!tracker_) return;
  tracker_->apply(update);
  if (update.correction) {
    ++corrections_;
    in_flight_.heard(now_s);
  } else {
    in_flight_.answered(now_s);
  }
}

}  // namespace binloop
