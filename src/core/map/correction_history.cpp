#include "binloop/map/correction_history.h"

#include "binloop/map/ancestors.h"
#include "binloop/messages/message_state.h"
#include "binloop/util/sorted_keys.h"

#include <stdexcept>
#include <string>

namespace binloop {

void CorrectionHistory::begin(uint64_t sequence) {
  if (sequence != applied() + 1) {
    throw std::invalid_argument("correction " + std::to_string(sequence) + " after " +
                                std::to_string(applied()) + " applied: one between is missing");
  }
  deltas_.emplace_back();
}

void CorrectionHistory::catchUp(uint64_t sequence) {
  while (applied() < sequence) deltas_.emplace_back();
}

void CorrectionHistory::note(SlamKeyframeId id, const Pose3& delta) {
  if (deltas_.empty()) throw std::logic_error("CorrectionHistory::note before begin");
  deltas_.back()[id] = delta;
}

Pose3 CorrectionHistory::since(uint64_t seen, SlamKeyframeId anchor) const {
  Pose3 d = Pose3::Identity();
  for (uint64_t k = seen; k < applied(); ++k) {
    auto it = deltas_[k].find(anchor);
    if (it != deltas_[k].end()) d = it->second * d;
  }
  return d;
}

Pose3 CorrectionHistory::adopt(uint64_t seen, SlamKeyframeId id, SlamKeyframeId anchor,
                               const std::function<SlamKeyframeId(SlamKeyframeId)>& up) {
  Pose3 d = Pose3::Identity();
  for (uint64_t k = seen; k < applied(); ++k) {
    const SlamKeyframeId a =
        up ? firstAncestor(anchor, up, [&](SlamKeyframeId x) { return deltas_[k].count(x) > 0; }) : anchor;
    auto it = deltas_[k].find(a);
    if (it == deltas_[k].end()) continue;
    d = it->second * d;
    deltas_[k][id] = it->second;
  }
  return d;
}

}  // namespace binloop

namespace binloop {

void CorrectionHistory::save(StateWriter& w) const {
  w.put<uint64_t>(deltas_.size());
  for (const auto& d : deltas_) {
    w.put<uint64_t>(d.size());
    for (SlamKeyframeId id : sortedKeys(d)) {
      w.put<uint64_t>(id);
      writePose(w, d.at(id));
    }
  }
}

void CorrectionHistory::load(StateReader& r) {
  deltas_.assign(r.getCount("corrections", 8), {});
  for (auto& d : deltas_) {
    const uint64_t n = r.getCount("corrected keyframes", 64);
    for (uint64_t i = 0; i < n; ++i) {
      const SlamKeyframeId id = r.get<uint64_t>("corrected keyframe");
      d[id] = readPose(r, "correction");
    }
  }
}

}  // namespace binloop
