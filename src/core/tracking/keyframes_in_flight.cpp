#include "binloop/tracking/keyframes_in_flight.h"

#include "binloop/util/fixed_decimals.h"

namespace binloop {

std::string KeyframesInFlight::giveUpIfStale(double now_s, bool mapping_listens) {
  if (count_ == 0) return "";
  std::string why;
  if (!mapping_listens) {
    why =
        "no local mapping subscribes to the keyframes: the last " + std::to_string(count_) + " are given up";
  } else if (now_s - last_contact_s_ > timeout_s_) {
    why = "local mapping answered none of the last " + std::to_string(count_) + " keyframes for " +
          fixedDecimals(timeout_s_, 1) + " s (~keyframe_timeout_s): they are given up";
  } else {
    return "";
  }
  given_up_ += static_cast<uint64_t>(count_);
  count_ = 0;
  last_contact_s_ = now_s;
  return why;
}

}  // namespace binloop
