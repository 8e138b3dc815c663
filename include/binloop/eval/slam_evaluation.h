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
std::vector<RevisitSegment> revisitSegments(const std::vector<std::pair<int, int>>& pairs,
                                            int max_gap = kRevisitMaxGap);

/// Whether the ground-truth positions of frames `query` and `match` lie within `radius_m`. Throws DataError
/// when a frame is outside the ground truth (e.g. the run was of another sequence).
bool loopIsCorrect(int query, int match, const std::vector<Pose3>& gt, double radius_m = kLoopCorrectRadiusM);

/// A loop's relative pose against the ground truth's: how far the verified T_query_match is from
/// T_w_query^-1 * T_w_match of the ground truth, in translation (m) and rotation (degrees).
struct LoopPoseError {
  double translation_m = 0, rotation_deg = 0;
};
/// Throws DataError when a frame is outside the ground truth.
LoopPoseError loopPoseError(int query, int match, const Pose3& T_query_match, const std::vector<Pose3>& gt);

/// A loop is wrong when its relative pose is off by more than this, wherever its two frames are: a loop
/// between frames 8 m apart whose pose is right corrects the map; one 2 m apart with a wrong pose bends it.
constexpr double kLoopWrongPoseM = 1.0;
constexpr double kLoopWrongPoseDeg = 2.0;
inline bool loopPoseIsWrong(const LoopPoseError& e) {
  return e.translation_m > kLoopWrongPoseM || e.rotation_deg > kLoopWrongPoseDeg;
}

struct LoopScore {
  int accepted = 0, correct = 0;
  int wrong_pose =
      0;  // accepted loops whose relative pose is wrong (loopPoseIsWrong); only when poses were given
  std::vector<bool> closed;  // one per segment
  int segmentsClosed() const;
};

/// Scores `accepted`, the (query_frame, match_frame) of every loop a run accepted, against the ground truth
/// and its revisit segments.
LoopScore scoreLoops(const std::vector<std::pair<int, int>>& accepted, const std::vector<Pose3>& gt,
                     const std::vector<RevisitSegment>& segments, double radius_m = kLoopCorrectRadiusM);

/// The same, also judging each loop's relative pose (`T_query_match[i]` for `accepted[i]`): a loop with a
/// wrong pose counts in wrong_pose and, whatever its distance, neither as correct nor as closing a segment.
LoopScore scoreLoops(const std::vector<std::pair<int, int>>& accepted,
                     const std::vector<Pose3>& T_query_match, const std::vector<Pose3>& gt,
                     const std::vector<RevisitSegment>& segments, double radius_m = kLoopCorrectRadiusM);

}  // namespace binloop
