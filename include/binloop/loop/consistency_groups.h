#pragma once
// ORB-SLAM2's consistency check of loop candidates (LoopClosing::DetectLoop): a candidate is accepted only
// when the queries before it proposed candidates in the same place, `required` times in a row. A "place"
// is a candidate's group, itself and its covisible keyframes; two proposals are consistent when their
// groups share a keyframe. One wrong proposal is common, the same wrong place four keyframes running is not.
#include <set>
#include <utility>
#include <vector>

#include "binloop/map/ids.h"

namespace binloop {

class ConsistencyGroups {
 public:
  using Group = std::set<SlamKeyframeId>;
  struct Proposal {
    SlamKeyframeId candidate;
    Group group;  // the candidate and its covisible keyframes
  };
  struct Result {
    SlamKeyframeId accepted = kNoId;  // the first candidate whose chain reached `required`
    int longest = 0;                  // the longest chain among this query's candidates
  };

  explicit ConsistencyGroups(int required = 3) : required_(required) {}
  /// One query's proposals (candidates that passed the model's bar), best first. A query without any
  /// clears every chain.
  Result update(const std::vector<Proposal>& proposals);
  void clear() { groups_.clear(); }

 private:
  int required_;
  std::vector<std::pair<Group, int>> groups_;  // the previous query's groups with their chain lengths
};

}  // namespace binloop
