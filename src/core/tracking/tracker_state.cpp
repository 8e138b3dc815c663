// Tracker's save/load (tracking's state file).
#include "binloop/features/orb_slam_extractor.h"
#include "binloop/io/state_file.h"
#include "binloop/messages/message_state.h"
#include "binloop/tracking/tracker.h"

namespace binloop {

void Tracker::save(StateWriter& w) const {
  writeCamera(w, cam_);
  w.putString(extractorSettings(p_.orb, 0).describe());
  w.put<uint64_t>(keyframe_ids_.issued());
  w.put<uint64_t>(point_ids_.issued());
  w.put<uint64_t>(corrections_seen_);
  map_.save(w);
  w.put<uint8_t>(keyframe_db_ ? 1 : 0);
  if (keyframe_db_) {
    w.putString(p_.vocabulary_identity);
    keyframe_db_->save(w);
  }
}

void Tracker::load(StateReader& r) {
  if (state_ != msg::TrackingState::kNotInitialized)
    r.fail("tracking has started already; a map loads into a new tracker");
  const StereoCamera cam = readCamera(r);
  if (!(cam == cam_)) {
    r.fail("the map was made with another camera:\n" + cam.describe() + "\nthis tracker has\n" +
           cam_.describe());
  }
  std::string extractor = r.getString("extractor");
  // Maps saved before the BRIEF pattern became a setting (2026-11-25) name the Gaussian tests "binloop ORB
  // (": the same descriptors as "binloop ORB with the Gaussian BRIEF pattern (".
  const std::string old_name = "binloop ORB (";
  if (extractor.rfind(old_name, 0) == 0)
    extractor = "binloop ORB with the Gaussian BRIEF pattern (" + extractor.substr(old_name.size());
  const std::string mine = extractorSettings(p_.orb, 0).describe();
  if (extractor != mine) {
    r.fail("the map's descriptors come from " + extractor + ", but this tracker extracts with " + mine +
           ": they would not match (use the orb settings the map was made with)");
  }
  keyframe_ids_.restore(r.get<uint64_t>("keyframe ids issued"));
  point_ids_.restore(r.get<uint64_t>("point ids issued"));
  corrections_seen_ = r.get<uint64_t>("corrections applied");
  map_.load(r);
  const bool has_index = r.get<uint8_t>("relocalisation index") != 0;
  if (has_index) {
    const std::string voc = r.getString("relocalisation vocabulary");
    if (keyframe_db_) {
      if (!voc.empty() && !p_.vocabulary_identity.empty() && voc != p_.vocabulary_identity) {
        r.fail("the map's relocalisation index was made with " + voc + ", but this tracker's vocabulary is " +
               p_.vocabulary_identity + " (load the map with the vocabulary it was made with)");
      }
      keyframe_db_->load(r);
    } else {
      KeyframeDatabase(nullptr).load(r);  // read past it: relocalisation then tries the most recent keyframes
    }
  } else if (keyframe_db_) {
    r.fail(
        "the map has no relocalisation index (it was saved by a tracker without a vocabulary), so this "
        "tracker's vocabulary could not find its places; load it with reloc_vocab none");
  }
  r.expectEnd();
  startLostAtLastKeyframe();
}

void Tracker::startLostAtLastKeyframe() {
  // The next frame is searched for around the last keyframe, then relocalised anywhere.
  state_ = msg::TrackingState::kLost;
  reference_ = last_ref_ = map_.lastKeyframe();
  T_ref_last_ = Pose3::Identity();
  last_ = std::make_unique<Frame>();
  if (const msg::KeyframeState* ref = map_.keyframe(reference_)) last_->T_w_c = ref->T_w_c;
  have_velocity_ = false;
  have_stamp_ = false;
}

bool Tracker::givesWayTo(const msg::LocalMapUpdate& whole) const {
  if (state_ == msg::TrackingState::kNotInitialized) return true;
  return map_.keyframeCount() <= 2 && whole.keyframes.size() > map_.keyframeCount();
}

void Tracker::adoptMap(const msg::LocalMapUpdate& whole) {
  if (state_ != msg::TrackingState::kNotInitialized)
    throw std::invalid_argument("tracking has started already; a map is adopted by a new tracker");
  map_.apply(whole);
  corrections_seen_ = whole.corrections_seen;
  merges_seen_ = whole.merges_seen;
  // A tracker restarted alone counts its ids from 1 again, and mapping refuses ids it holds: go on after
  // the highest of this tracker's issuer in the map.
  // It has issued none yet, but a tracker that took another's place counts in a new session already.
  keyframe_ids_.restore(whole.tracking_keyframe_ids);
  point_ids_.restore(whole.tracking_point_ids);
  if (map_.keyframeCount() > 0) startLostAtLastKeyframe();
}

void Tracker::continueIdsInNewSession(uint64_t keyframes, uint64_t points) {
  keyframe_ids_.startSessionAfter(keyframes);
  point_ids_.startSessionAfter(points);
}

StereoCamera Tracker::savedCamera(const std::string& path) {
  StateReader r(path, "tracking");
  return readCamera(r);
}

}  // namespace binloop
