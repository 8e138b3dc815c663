#include "binloop/tracking/tracking_stage.h"

#include <utility>

namespace binloop {

TrackingStage::TrackingStage(TrackerParams params, std::optional<StereoCamera> camera,
                             double keyframe_timeout_s, size_t resend_window)
    : params_(std::move(params)),
      fixed_camera_(camera),
      resend_window_(resend_window),
      in_flight_(keyframe_timeout_s) {
  if (fixed_camera_) tracker_ = freshTracker(*fixed_camera_);
}

std::unique_ptr<Tracker> TrackingStage::freshTracker(const StereoCamera& camera) const {
  return std::make_unique<Tracker>(camera, params_);
}

void TrackingStage::replaceTracker(std::unique_ptr<Tracker> t) {
  if (tracker_) {  // it went on from those before it, so its counts are the stage's highest
    keyframe_ids_ = tracker_->keyframeIdsIssued();
    point_ids_ = tracker_->pointIdsIssued();
  }
  tracker_ = std::move(t);
  if (tracker_ && (keyframe_ids_ > 0 || point_ids_ > 0))
    tracker_->continueIdsInNewSession(keyframe_ids_, point_ids_);
}

void TrackingStage::setCamera(const StereoCamera& camera) {
  replaceTracker(freshTracker(camera));
  if (kept_) adopt(std::exchange(kept_, nullptr));
}

TrackingStage::Adopted TrackingStage::adopt(msg::LocalMapUpdatePtr whole) {
  if (!tracker_) {
    kept_ = std::move(whole);
    return Adopted::kKept;
  }
  if (!tracker_->givesWayTo(*whole)) return behind(*whole) ? Adopted::kBehind : Adopted::kIgnored;
  const bool started = tracker_->state() != msg::TrackingState::kNotInitialized;
  if (started) startOver(freshTracker(tracker_->camera()));
  tracker_->adoptMap(*whole);
  ++maps_adopted_;
  return started ? Adopted::kTakenAfterStartOver : Adopted::kTaken;
}

bool TrackingStage::behind(const msg::LocalMapUpdate& whole) {
  // The map holds this tracker's keyframes up to counter `held` (tracker ids only go up, so it holds
  // none after it).
  const uint64_t held = whole.tracking_keyframe_ids;
  resend_.clear();
  resend_missing_ = 0;
  for (const msg::KeyFramePtr& k : sent_) {
    if (issuerOf(k->id) != IdIssuer::kTracking || counterOf(k->id) <= held) continue;
    if (resend_.empty()) resend_missing_ = counterOf(k->id) - (held + 1);  // sent, but no longer kept
    resend_.push_back(k);
  }
  return !resend_.empty();
}

std::vector<msg::KeyFramePtr> TrackingStage::takeResend(double now_s, uint64_t* missing) {
  // Not counted in flight: tracking must go on making keyframes while mapping works through them (a
  // hundred take it seconds). Their answers may then free a slot early, which only sends one sooner.
  if (!resend_.empty()) in_flight_.heard(now_s);
  if (missing) *missing = resend_missing_;
  resent_ += resend_.size();
  not_resent_ += resend_missing_;
  resend_missing_ = 0;
  return std::exchange(resend_, {});
}

void TrackingStage::startOver(std::unique_ptr<Tracker> tracker) {
  kept_.reset();
  sent_.clear();
  resend_.clear();
  replaceTracker(std::move(tracker));
  in_flight_.clear();
}

void TrackingStage::reset() { startOver(fixed_camera_ ? freshTracker(*fixed_camera_) : nullptr); }

Tracker::Output TrackingStage::track(const StereoFrame& frame, double now_s) {
  Tracker::Output out = tracker_->track(frame, in_flight_.count());
  if (out.keyframe) {
    in_flight_.sent(now_s);
    sent_.push_back(out.keyframe);
    if (sent_.size() > resend_window_) sent_.pop_front();
  }
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
