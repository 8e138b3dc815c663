#pragma once
// The corrections loop closing sent, kept until local mapping shows it applied them. A correction can be
// lost on the way (local mapping's process restarted from an autosave made before it, a message dropped
// between processes) or refused (it came after a lost one: mapping applies them in sequence only). Then
// every later correction would be refused too, and the two stages would disagree for good. Local mapping
// says in each update how many corrections it had applied (LocalMapUpdate::corrections_seen); while those
// are behind what was sent, the updates are counted, and after `resend_after_updates` of them the
// corrections mapping lacks are sent again. A correction merely on its way is not lost: mapping's queue
// holds a few keyframes at most (tracking's keyframes in flight), so the count is set above that, and a
// correction that arrives twice is applied once (LocalMapper::apply).
#include <cstddef>
#include <cstdint>
#include <deque>
#include <vector>

#include "binloop/messages/correction.h"

namespace binloop {

class CorrectionOutbox {
 public:
  /// Corrections kept by default: a publisher of corrections needs a queue at least this long, or a resend
  /// of them all would drop the oldest.
  static constexpr size_t kKept = 32;
  explicit CorrectionOutbox(int resend_after_updates = 8, size_t kept = kKept);
  /// A correction just sent (sequence one after the last).
  void sent(const msg::CorrectionPtr& c);
  /// An update local mapping made after applying `seen` corrections: the corrections to send again (in
  /// sequence), or none. `*gap` (if given) is set when mapping lacks corrections no longer kept: those
  /// cannot be sent again and mapping will refuse the later ones.
  std::vector<msg::CorrectionPtr> mappingSaw(uint64_t seen, bool* gap = nullptr);
  uint64_t lastSent() const { return kept_.empty() ? 0 : kept_.back()->sequence; }
  /// Corrections sent again so far.
  uint64_t resent() const { return resent_; }

 private:
  int resend_after_;
  size_t keep_;
  std::deque<msg::CorrectionPtr> kept_;
  int behind_ = 0;  // updates in a row that lacked a sent correction
  uint64_t resent_ = 0;
};

}  // namespace binloop
