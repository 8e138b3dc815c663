#pragma once
// Geometric verification of a loop candidate (the first half of loop closing): do the query keyframe
// and the candidate keyframe see the same 3-D structure, and where is one camera relative to the other?
// Stereo gives both keyframes metric 3-D points of their own, so the answer is a rigid transform:
//   1. descriptor matches between their stereo keypoints (best below max_hamming, clearly better than the
//      second): within each coarse word when the detector's model gives words (hbow: ORB-SLAM2's
//      SearchByBoW), else brute force over ~2000 x 2000 (place/descriptor_block.h, ~1 ms with AVX-512);
//   2. RANSAC (seeded) over Horn's closed form on the matched 3-D points;
//   3. refinement by pose optimisation: the candidate's points, in its camera frame, reprojected into the
//      query's keypoints (optim/pose_optimizer.h, robust loss, outliers dropped);
//   4. guided search: the candidate's unmatched stereo points projected into the query with that pose, a
//      match searched near each, and the pose refined again;
//   5. accepted when the final inliers reach min_inliers (ORB-SLAM2: 40).
// A rejection says at which step.
#include <string>
#include <vector>

#include "binloop/messages/keyframe.h"
#include "binloop/messages/loop_closure.h"
#include "binloop/optim/pose_optimizer.h"
#include "binloop/optim/rigid_alignment.h"
#include "binloop/types/pose.h"

namespace binloop {

enum class LoopRejection { kNone, kTooFewMatches, kNoConsensus, kTooFewInliers };
/// The loop status a verification ends with (kNone: accepted).
msg::LoopStatus loopStatusOf(LoopRejection r);

struct LoopVerifierParams {
  int max_hamming = 50;        // ORB-SLAM2's TH_LOW
  float ratio = 0.75f;         // best vs second best
  int min_matches = 20;        // descriptor matches needed before RANSAC
  bool match_by_words = true;  // match within the words given with the keyframes (none given: brute force)
  RigidRansacParams ransac;
  float search_radius = 10;  // guided search, level-0 px times the level's scale
  int min_inliers = 40;
  // Refinement starts from RANSAC's pose, which is already close: two rounds (robust, then plain) of at most
  // 5 iterations instead of tracking's 4 x 10 (synthetic 2000 x 2000 keyframes: 7.7 -> ms per refinement),
  // each solved on at most 200 of the pairs and judging all of them.
  PoseOptimizerParams refine = [] {
    PoseOptimizerParams r{2, 5, 1};
    r.max_solve_observations = 200;
    return r;
  }();
  uint64_t seed = 1;
};

struct LoopVerification {
  bool accepted = false;
  LoopRejection rejection = LoopRejection::kNone;
  std::string detail;                           // the numbers behind the result, one line
  Pose3 T_query_candidate = Pose3::Identity();  // candidate camera -> query camera
  int matches = 0;                              // step 1
  bool by_words = false;                        // step 1 matched within words
  int first_inliers = 0;  // inliers of the first pose: step 2's RANSAC (verifyLoopAt: the first refinement's)
  int inliers = 0;        // after step 4
  std::vector<std::pair<int, int>> pairs;  // final inlier (query keypoint, candidate keypoint) pairs
  double ms = 0;
  double match_ms = 0, ransac_ms = 0, refine_ms = 0, guided_ms = 0;  // steps 1, 2, 3, 4 (+ final refinement)
};

/// Both keyframes must carry keypoints with stereo depth; `scale_factor` and `levels` from the messages.
/// `query_words` and `candidate_words`: a coarse word per keypoint (msg::LoopCandidates), or empty; words
/// whose count differs from the keypoints' are not used (the detail says so).
LoopVerification verifyLoop(const msg::KeyFrame& query, const msg::KeyFrame& candidate,
                            const LoopVerifierParams& p, const std::vector<uint32_t>& query_words = {},
                            const std::vector<uint32_t>& candidate_words = {});

/// Steps 4 and 5 only, from a pose already known to be close (a verified loop carried to a keyframe beside
/// its match through the map): guided search, refinement, a second guided search and refinement.
/// `matches` counts the first search, `first_inliers` what the first refinement kept (there is no RANSAC).
LoopVerification verifyLoopAt(const msg::KeyFrame& query, const msg::KeyFrame& candidate,
                              const Pose3& T_guess, const LoopVerifierParams& p);

}  // namespace binloop
