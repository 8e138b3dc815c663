#pragma once
// What each loop correction did to each keyframe, so that a message made before a correction (a keyframe
// tracking made while loop closing was optimising, an update local mapping sent meanwhile) can be brought
// into the corrected map when it arrives: its pose moves as its parent keyframe's did. Every stage that
// receives corrections keeps one; in lock-step no message is ever late and none of this is used.
#include <functional>
#include <unordered_map>
#include <vector>

#include "binloop/map/ids.h"
#include "binloop/types/pose.h"

namespace binloop {

class StateWriter;
class StateReader;

class CorrectionHistory {
 public:
  /// Starts correction `sequence` (1, 2, ...: each follows the one before).
  void begin(uint64_t sequence);
  /// Keyframe `id` moved by `delta` (T_after * T_before^-1, world frame) in the current correction.
  void note(SlamKeyframeId id, const Pose3& delta);
  uint64_t applied() const { return static_cast<uint64_t>(deltas_.size()); }
  /// Counts corrections up to `sequence` as applied without knowing what they did (they moved nothing this
  /// history knows of): for a stage that started after them, so that its sequence agrees with the map's
  /// again. Nothing happens when `sequence` is not ahead.
  void catchUp(uint64_t sequence);

  /// The world-frame change, since its creator had applied `seen` corrections, of a pose that rides on
  /// keyframe `anchor`: the corrections after `seen`, composed in order. Identity when none is missing or
  /// a correction did not know the anchor.
  Pose3 since(uint64_t seen, SlamKeyframeId anchor) const;
  /// since(), and records that keyframe `id` (made late) moved with `anchor` in those corrections, so that
  /// keyframes made on it later move the same way. `up` gives the parent a culled keyframe had (kNoId for
  /// none): an anchor culled before a correction is not in it, and the pose moves as the nearest ancestor
  /// that is.
  Pose3 adopt(uint64_t seen, SlamKeyframeId id, SlamKeyframeId anchor,
              const std::function<SlamKeyframeId(SlamKeyframeId)>& up = {});

  void save(StateWriter& w) const;
  void load(StateReader& r);

 private:
  std::vector<std::unordered_map<SlamKeyframeId, Pose3>> deltas_;  // [sequence - 1]
};

}  // namespace binloop
