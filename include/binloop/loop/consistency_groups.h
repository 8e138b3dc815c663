#pragma once
// ORB-SLAM2's consistency check of loop candidates (LoopClosing::DetectLoop): a candidate is accepted only
// when the queries before it proposed candidates in the same place, `required` times in a row. A "place"
// is a candidate's group, itself and its covisible keyframes; two proposals are consistent when their
// groups share a keyframe. One wrong proposal is common, the same wrong place four keyframes running is not.
// Departure (`max_gap`): a chain survives up to max_gap queries that do not continue it (no proposal, or
// proposals elsewhere) instead of ending at the first. At the camera's rate the models' bar lets a revisit
// through every second or third keyframe (rendered 00's first revisit, frames 1557-1643, at 1x: hmvlad
// proposed the right place at 1577, 1582 and 1590 with one query below the bar between, and never
// reached 2 in a row), so short revisits at the end of a drive were never verified.
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

  explicit ConsistencyGroups(int required = 3, int max_gap = 0) : required_(required), max_gap_(max_gap) {}
  /// One query's proposals (candidates that passed the model's bar), best first. A chain that this query
  /// does not continue ages by one and ends after max_gap such queries.
  Result update(const std::vector<Proposal>& proposals);
  void clear() { groups_.clear(); }

 private:
  struct Chain {
    Group group;  // the place of its last proposal
    int length;   // consistent proposals after the first
    int age;      // queries since it was last continued
  };
  int required_, max_gap_;
  std::vector<Chain> groups_;
};

}  // namespace binloop
