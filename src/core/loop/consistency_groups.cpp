#include "binloop/loop/consistency_groups.h"

#include <algorithm>

namespace binloop {

namespace {

bool intersects(const std::set<SlamKeyframeId>& a, const std::set<SlamKeyframeId>& b) {
  auto i = a.begin(), j = b.begin();
  while (i != a.end() && j != b.end()) {
    if (*i == *j) return true;
    if (*i < *j) {
      ++i;
    } else {
      ++j;
    }
  }
  return false;
}

}  // namespace

ConsistencyGroups::Result ConsistencyGroups::update(const std::vector<Proposal>& proposals) {
  Result r;
  std::vector<Chain> next;
  std::vector<bool> continued(groups_.size(), false);
  for (const Proposal& p : proposals) {
    bool consistent_with_some = false;
    for (size_t g = 0; g < groups_.size(); ++g) {
      if (!intersects(p.group, groups_[g].group)) continue;
      consistent_with_some = true;
      const int length = groups_[g].length + 1;
      r.longest = std::max(r.longest, length);
      // Each previous group continues once, through the first (best) proposal that meets it.
      if (!continued[g]) {
        next.push_back({p.group, length, 0});
        continued[g] = true;
      }
      if (length >= required_ && r.accepted == kNoId) r.accepted = p.candidate;
    }
    if (!consistent_with_some) next.push_back({p.group, 0, 0});
  }
  for (size_t g = 0; g < groups_.size(); ++g) {
    if (!continued[g] && groups_[g].age < max_gap_)
      next.push_back({groups_[g].group, groups_[g].length, groups_[g].age + 1});
  }
  groups_ = std::move(next);
  return r;
}

}  // namespace binloop
