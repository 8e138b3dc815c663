#include "binloop/loop/correction_outbox.h"

#include <stdexcept>

namespace binloop {

CorrectionOutbox::CorrectionOutbox(int resend_after_updates, size_t kept)
    : resend_after_(resend_after_updates), keep_(kept) {
  if (resend_after_updates < 1 || kept < 1)
    throw std::invalid_argument("correction outbox: resend_after_updates and kept must be at least 1");
}

void CorrectionOutbox::sent(const msg::CorrectionPtr& c) {
  if (!c) return;
  kept_.push_back(c);
  while (kept_.size() > keep_) kept_.pop_front();
  behind_ = 0;  // the new one is on its way: mapping gets its usual time for it
}

std::vector<msg::CorrectionPtr> CorrectionOutbox::mappingSaw(uint64_t seen, bool* gap) {
  if (gap) *gap = false;
  if (seen >= lastSent()) {
    behind_ = 0;
    return {};
  }
  if (++behind_ < resend_after_) return {};
  behind_ = 0;
  std::vector<msg::CorrectionPtr> again;
  for (const msg::CorrectionPtr& c : kept_)
    if (c->sequence > seen) again.push_back(c);
  if (gap && !again.empty() && again.front()->sequence > seen + 1) *gap = true;
  resent_ += again.size();
  return again;
}

}  // namespace binloop
