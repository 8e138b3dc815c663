// LoopCloser's save/load (the loop-closing stage's state file).
#include <algorithm>

#include "binloop/io/state_file.h"
#include "binloop/loop/loop_closer.h"
#include "binloop/messages/message_state.h"

namespace binloop {

void LoopCloser::save(StateWriter& w) const {
  w.put<uint64_t>(order_.size());
  for (SlamKeyframeId id : order_) {
    writeKeyFrame(w, *frames_.at(id));
    writeKeyframeState(w, states_.at(id));
  }
  w.put<uint64_t>(loops_.size());
  for (const LoopEdge& e : loops_) {
    w.put<uint64_t>(e.query);
    w.put<uint64_t>(e.candidate);
    writePose(w, e.T_query_candidate);
  }
  history_.save(w);
  w.put<uint64_t>(first_);
  w.put<uint64_t>(last_correction_at_);
  std::vector<std::pair<SlamKeyframeId, SlamKeyframeId>> culled(culled_.begin(), culled_.end());
  std::sort(culled.begin(), culled.end());  // one state, one file
  w.put<uint64_t>(culled.size());
  for (const auto& [k, parent] : culled) {
    w.put<uint64_t>(k);
    w.put<uint64_t>(parent);
  }
}

void LoopCloser::load(StateReader& r) {
  if (!order_.empty()) r.fail("the loop-closing stage already holds keyframes; a map loads into a new one");
  const uint64_t n = r.getCount("keyframes", 100);
  for (uint64_t i = 0; i < n; ++i) {
    auto kf = std::make_shared<const msg::KeyFrame>(readKeyFrame(r));
    msg::KeyframeState s = readKeyframeState(r);
    if (s.id != kf->id || states_.count(kf->id))
      r.fail("keyframe " + std::to_string(kf->id) + " twice or mislabelled");
    states_[kf->id] = std::move(s);
    order_.push_back(kf->id);
    frames_[kf->id] = std::move(kf);
  }
  loops_.resize(r.getCount("loops", 72));
  for (LoopEdge& e : loops_) {
    e.query = r.get<uint64_t>("loop query");
    e.candidate = r.get<uint64_t>("loop match");
    e.T_query_candidate = readPose(r, "loop pose");
  }
  history_.load(r);
  first_ = r.get<uint64_t>("first keyframe");
  last_correction_at_ = r.get<uint64_t>("keyframes at the last correction");
  const uint64_t culled = r.getCount("culled keyframes", 16);
  for (uint64_t i = 0; i < culled; ++i) {
    const SlamKeyframeId k = r.get<uint64_t>("culled keyframe");
    culled_[k] = r.get<uint64_t>("culled keyframe's parent");
  }
  r.expectEnd();
}

}  // namespace binloop
