#pragma once
// Keyframe and map-point ids. Stages run apart (threads, processes, machines) and each creates entities
// without asking the others, so an id carries the stage that issued it in its top byte and a counter in
// the rest: two stages never collide and no id is ever reused. 0 means "none".
#include <algorithm>
#include <cstdint>

namespace binloop {

using SlamKeyframeId = uint64_t;
using MapPointId = uint64_t;
constexpr uint64_t kNoId = 0;

/// Who issued an id (the top byte). Values are part of the message format: never renumber.
enum class IdIssuer : uint8_t { kTracking = 1, kLocalMapping = 2, kLoopClosing = 3 };

inline IdIssuer issuerOf(uint64_t id) { return static_cast<IdIssuer>(id >> 56); }
inline uint64_t counterOf(uint64_t id) { return id & ((uint64_t{1} << 56) - 1); }

/// Issues ids 1, 2, 3, ... of one stage.
class IdCounter {
 public:
  explicit IdCounter(IdIssuer who) : base_(uint64_t(static_cast<uint8_t>(who)) << 56) {}
  uint64_t next() { return base_ | ++count_; }
  uint64_t issued() const { return count_; }
  /// Continues after `issued` ids (a loaded map, a map adopted), so that no id is issued twice; a counter
  /// already past them stays where it is (it never goes back).
  void restore(uint64_t issued) { count_ = std::max(count_, issued); }
  /// Jumps to the next multiple of 2^32 (a new session of this issuer): a stage restored from a state file
  /// older than the ids it had issued before it stopped (an autosave) issues none of those again, though it
  /// cannot know how many there were. 2^24 sessions of 2^32 ids each.
  void startSession() { count_ = ((count_ >> 32) + 1) << 32; }
  /// A new session after `issued` ids of another counter of the same issuer and after this one's own: for a
  /// stage that takes another's place (a reset, a loaded map) while ids of the other may still be in flight.
  void startSessionAfter(uint64_t issued) {
    restore(issued);
    startSession();
  }

 private:
  uint64_t base_;
  uint64_t count_ = 0;
};

}  // namespace binloop
