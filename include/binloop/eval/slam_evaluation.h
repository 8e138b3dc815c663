#pragma once
// Scoring a SLAM run's loop closures against ground truth (eval-slam): is each accepted loop right, and
// which revisits of the route did the run close.
//
// A revisit segment is a maximal run of ground-truth query frames (the first frame of each loop pair) in
// which consecutive query frames differ by at most `max_gap` frames (default 20, 2 s of KITTI: a revisit
// that briefly leaves the ground truth's radius, e.g. at a crossing, stays one segment, while two passes
// of a street minutes apart do not merge). A segment is closed when at least one correct accepted loop
// has its query frame in [first, last]. A loop is correct when the ground-truth positions of its two
// frames lie within 10 m.
#include <utility>
#include <vector>

#include "binloop/types/pose.h"

namespace binloop {

constexpr int kRevisitMaxGap = 20;
constexpr double kLoopCorrectRadiusM = 10.0;

struct RevisitSegment {
  int first = 0, last = 0;  // query frames, inclusive
  int queries = 0;          // distinct query frames in it
};

/// Segments of the (query, ref) pairs' query frames, in frame order. Pairs may come in any order.
std::vector<RevisitSegment> revisitSegments(const std::vector<std::pair<int, int>>& pairs, int max_gap = kRevisitMaxGap);

/// Whether the ground-truth positions of frames `query` and `match` lie within `radius_m`. Throws DataError
/// when a frame is outside the ground truth (e.g. the run was of another sequence).
bool loopIsCorrect(int query, int match, const std::vector<Pose3>& gt, double radius_m = kLoopCorrectRadiusM);

struct LoopScore {
  int accepted = 0, correct = 0;
  std::vector<bool> closed;  // one per segment
  int segmentsClosed() const;
};

/// Scores `accepted`, the (query_frame, match_frame) of every loop a run accepted, against the ground truth
/// and its revisit segments.
LoopScore scoreLoops(const std::vector<std::pair<int, int>>& accepted, const std::vector<Pose3>& gt,
                     const std::vector<RevisitSegment>& segments, double radius_m = kLoopCorrectRadiusM);

}  // namespace binloop
