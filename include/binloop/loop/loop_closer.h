#pragma once
// The loop-closing stage (step 4 of four; ARCHITECTURE.md): refined keyframes and local mapping's updates in
// (its own copy of every keyframe: keypoints, descriptors, pose, covisibility, parent), the loop detector's
// accepted candidates in; per verified loop a LoopClosure out, and for an accepted one a Correction for local
// mapping.
//
// A loop is accepted in four steps:
//   1. verification (loop/loop_verifier.h): the two keyframes see the same structure; T_query_match. A pair
//      more than reanchor_min_m apart is verified again with the match's covisible keyframe nearest to the
//      query, which becomes the match when it verifies;
//   2. the drift bound: the loop moves the query keyframe by `correction_m`; odometry is trusted to have
//      drifted by at most drift_base_m + drift_per_m * (the shortest path from the match to the query
//      through the keyframe chain and the loops closed so far). A loop beyond it, but within hold_factor
//      times it, is held until a second loop, at least confirm_min_travel_m further on, asks for the same
//      correction (within confirm_tolerance_m plus confirm_tolerance_per_m of the path between the two
//      queries); a loop that agrees with the held one but comes less than confirm_min_travel_m after it
//      waits with it (agreed, once confirmed); a held loop that nothing confirms within hold_keyframes is
//      rejected with those that agreed, and so is at once a loop beyond hold_factor times the bound
//      (beyond_drift_bound).
//      Repeated facades pass step 1 between places hundreds of metres apart; they do not pass this. Nor
//      does a facade repeated a few metres along the street, which shifts a true revisit by that much
//      (rendered 00, frame 1571: 7.2 m along the road, accepted under a 2 % bound, then every correct loop
//      after it asked for the 7 m back). So the bound is tight, 2-3x the tracking's own drift, and a true
//      loop beyond it waits for a second one rather than being lost.
//   3. the essential graph (loop/essential_graph.h) optimised with the loop edge (optim/pose_graph.h);
//   4. the residual guard: residual_ratio = sqrt(chi2 of the loop edge after / before the optimisation),
//      the part of the loop's disagreement the graph could not absorb; above max_residual_ratio the loop
//      is rejected (large_residual) and nothing moves.
#include <deque>
#include <optional>
#include <unordered_map>
#include <vector>

#include "binloop/loop/correction_outbox.h"
#include "binloop/loop/essential_graph.h"
#include "binloop/loop/loop_verifier.h"
#include "binloop/map/correction_history.h"
#include "binloop/messages/correction.h"
#include "binloop/messages/keyframe.h"
#include "binloop/messages/local_map_update.h"
#include "binloop/messages/loop_candidates.h"
#include "binloop/messages/loop_closure.h"
#include "binloop/optim/pose_graph.h"
#include "binloop/place/place_recognizer.h"

namespace binloop {

class StateWriter;
class StateReader;

struct LoopCloserParams {
  LoopVerifierParams verify;
  EssentialGraphParams graph;
  PoseGraphParams optimizer;
  double drift_base_m = 1.0;
  double drift_per_m = 0.005;  // 2-3x the t_rel of the tracking on the rendered routes (0.16-0.21 %)
  double confirm_min_travel_m = 10;
  double hold_factor = 10;
  double confirm_tolerance_m = 1.0;
  double confirm_tolerance_per_m = 0.05;
  int hold_keyframes = 40;
  double max_residual_ratio = 0.5;
  int min_keyframes_between_loops = 5;  // after a correction, the next few proposals are not verified
  // A detector proposes the keyframe whose image looks most alike, which on a wide street can be one seen
  // 10 m down the road (rendered 00, frame 2431 -> 396: 11 m, though frame 381 passed 5 m away). Depth
  // error grows with distance squared, so the loop edge is measured against the match's covisible keyframe
  // nearest to the query when the verified pair is more than this far apart (0: never).
  double reanchor_min_m = 5;
  bool fuse = true;  // ask local mapping to merge the points around the loop
  // Local mapping's updates that may lack a sent correction before it is sent again (correction_outbox.h).
  int resend_corrections_after_updates = 8;
};

class LoopCloser {
 public:
  struct Output {
    std::vector<msg::LoopClosurePtr> closures;  // loops verified now (and held ones that expired)
    msg::CorrectionPtr correction;              // set when a loop was accepted
  };

  explicit LoopCloser(const LoopCloserParams& p = {});

  /// A refined keyframe from local mapping (a later revision replaces the stored one). Throws
  /// std::invalid_argument for a malformed message (sizes differ).
  void addKeyframe(const msg::KeyFramePtr& kf);
  /// Local mapping's later refinements of poses and covisibility, and its culled keyframes. Returns the
  /// corrections to send local mapping again, when its updates show it lacks some (correction_outbox.h);
  /// `*gap` (if given) says that some it lacks are no longer kept.
  std::vector<msg::CorrectionPtr> apply(const msg::LocalMapUpdate& u, bool* gap = nullptr);
  /// The active detector's result: verifies its accepted candidate, if any (shadow results are ignored).
  Output process(const msg::LoopCandidates& c);
  /// A loop proposed from outside (another front end, a person): verified and guarded the same way.
  Output addExternalLoop(SlamKeyframeId query, SlamKeyframeId match, const std::string& source = "external");
  /// The input has ended (the run is over, or the map is about to be replaced): a held loop and those that
  /// waited with it get their final status, beyond_drift_bound, since no second loop will confirm them.
  /// Safe to call more than once; the closer still answers later input.
  Output finish();

  size_t keyframeCount() const { return states_.size(); }
  struct KeyframePose {
    SlamKeyframeId id;
    double stamp_s;
    Pose3 T_w_c;
  };
  /// The keyframes it holds, in the order they arrived, with their poses now (corrected).
  std::vector<KeyframePose> keyframePoses() const;
  const std::vector<LoopEdge>& loops() const { return loops_; }
  uint64_t correctionsMade() const { return history_.applied(); }
  uint64_t correctionsResent() const { return outbox_.resent(); }

  /// Its keyframes (as refined and corrected), the loops closed and the corrections made. A held loop is not
  /// saved: it waits for a confirmation that a loaded map will not bring (finish() first reports it).
  void save(StateWriter& w) const;
  /// Into a newly made closer. Throws DataError for a broken file.
  void load(StateReader& r);

 private:
  struct Held {
    LoopEdge edge;
    msg::LoopClosure closure;
    Pose3 delta;                             // the world-frame correction it asks for
    size_t held_at = 0;                      // keyframes stored when it was held
    std::vector<msg::LoopClosure> agreeing;  // later loops that agree but came too soon to confirm it
  };
  Output verify(SlamKeyframeId query, SlamKeyframeId match, const std::string& model,
                const std::vector<uint32_t>& query_words = {}, const std::vector<uint32_t>& match_words = {});
  /// The geometric verification of a proposed pair (a culled match stood in for by its parent, a far
  /// match re-anchored): the verification when it holds, else none with `c`'s status and detail saying why.
  /// Fills `c`'s match, frames and numbers either way.
  std::optional<LoopVerification> verifyPair(SlamKeyframeId query, SlamKeyframeId match,
                                             const std::vector<uint32_t>& query_words,
                                             const std::vector<uint32_t>& match_words,
                                             msg::LoopClosure* c) const;
  /// The drift bound on a verified loop: true when the correction it asks for is one odometry's drift can
  /// explain, or when it confirms the held loop (`confirmed`: the held loop's edge); false when it is held
  /// (alone or beside the held loop it agrees with) or rejected, `c` and `out` saying so. `numbers`: the
  /// detail so far.
  bool withinDriftBound(SlamKeyframeId query, SlamKeyframeId match, const LoopVerification& v,
                        msg::LoopClosure* c, std::string* numbers, std::optional<LoopEdge>* confirmed,
                        Output* out);
  /// A verified loop between keyframes far apart is re-verified against the match's covisible keyframes
  /// nearest to the query; returns the keyframe the loop is anchored at, with *v its verification (its ms
  /// and detail count both searches).
  SlamKeyframeId reanchor(SlamKeyframeId query, SlamKeyframeId match, LoopVerification* v) const;
  /// The keyframe standing for `id`: itself, or for a culled keyframe its nearest held ancestor (kNoId when
  /// neither is held).
  SlamKeyframeId standIn(SlamKeyframeId id) const;
  double travelBetween(SlamKeyframeId a, SlamKeyframeId b) const;
  bool correct(const std::vector<LoopEdge>& new_loops,
               const std::vector<std::pair<MapPointId, MapPointId>>& fused, msg::LoopClosure* c, Output* out);
  void expireHeld(Output* out);
  /// The held loop, then those that agreed with it; nothing is held after.
  std::vector<msg::LoopClosure> takeHeld();
  /// Rejects the held loop and those that agreed with it (beyond_drift_bound, `why` added to each detail).
  void rejectHeld(const std::string& why, Output* out);

  LoopCloserParams p_;
  std::unordered_map<SlamKeyframeId, msg::KeyFramePtr> frames_;
  std::unordered_map<SlamKeyframeId, msg::KeyframeState> states_;
  std::vector<SlamKeyframeId> order_;  // arrival order (culled ones removed)
  // Culled keyframe -> its spanning-tree parent then: a proposal of a culled keyframe goes to the parent.
  std::unordered_map<SlamKeyframeId, SlamKeyframeId> culled_;
  std::vector<LoopEdge> loops_;
  std::optional<Held> held_;
  CorrectionHistory history_;
  CorrectionOutbox outbox_;
  SlamKeyframeId first_ = kNoId;
  size_t last_correction_at_ = 0;  // keyframes stored when the last correction was made
};

}  // namespace binloop
