#pragma once
// How many inverted-index lists name each keyframe slot: the common-word count of hbow and fabmap and
// the shared (word, code) count of vladpq. Counts live in a dense array (one per stored keyframe), and
// the slots met at all are kept apart, so a query never walks keyframes that share nothing with it.
#include <algorithm>
#include <cstdint>
#include <vector>

namespace binloop {

class SlotCounter {
 public:
  explicit SlotCounter(size_t slots) : count_(slots, 0) {}
  void add(const std::vector<uint32_t>& list) {
    for (uint32_t s : list)
      if (count_[s]++ == 0) touched_.push_back(s);
  }
  uint32_t operator[](uint32_t slot) const { return count_[slot]; }
  /// Every slot counted at least once, ascending, so that results never depend on the order lists came in.
  const std::vector<uint32_t>& touched() {
    std::sort(touched_.begin(), touched_.end());
    return touched_;
  }

 private:
  std::vector<uint32_t> count_;
  std::vector<uint32_t> touched_;
};

}  // namespace binloop
