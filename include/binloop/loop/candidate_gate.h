#pragma once
// Loop candidates wait for their keyframe. The detector's candidates for a keyframe can reach loop closing
// before the keyframe itself and the local-map update that goes with it (in the split graph each topic is
// its own connection, so messages overtake one another); closing must not verify against a keyframe it does
// not hold yet. Candidates are released in arrival order, each once loop closing has both its keyframe and
// its update; when `max_waiting` wait, the oldest is released unready (its keyframe never came) so that one
// lost keyframe does not hold every later loop. In one process (SlamPipeline) the keyframe, its update and
// its candidates are handed over together and nothing waits.
#include <cstddef>
#include <deque>
#include <optional>
#include <unordered_set>
#include <utility>

#include "binloop/map/ids.h"

namespace binloop {

template <class Candidates>
class CandidateGate {
 public:
  explicit CandidateGate(size_t max_waiting = 50) : max_waiting_(max_waiting) {}

  void keyframeArrived(SlamKeyframeId id) { keyframes_.insert(id); }
  void updateArrived(SlamKeyframeId id) { updates_.insert(id); }
  void push(SlamKeyframeId query, Candidates c) { waiting_.emplace_back(query, std::move(c)); }

  struct Released {
    Candidates candidates;
    bool ready = false;  // false: released because too many waited; its keyframe never came
  };
  /// The oldest waiting candidates, when their keyframe and update are here or the queue is full.
  std::optional<Released> next() {
    if (waiting_.empty()) return std::nullopt;
    const SlamKeyframeId query = waiting_.front().first;
    const bool ready = keyframes_.count(query) && updates_.count(query);
    if (!ready && waiting_.size() < max_waiting_) return std::nullopt;  // later ones wait for earlier ones
    Released r{std::move(waiting_.front().second), ready};
    waiting_.pop_front();
    return r;
  }

  size_t waiting() const { return waiting_.size(); }
  /// A loaded map or a reset: nothing waits, nothing has arrived.
  void clear() {
    waiting_.clear();
    keyframes_.clear();
    updates_.clear();
  }

 private:
  size_t max_waiting_;
  std::deque<std::pair<SlamKeyframeId, Candidates>> waiting_;
  std::unordered_set<SlamKeyframeId> keyframes_, updates_;
};

}  // namespace binloop
