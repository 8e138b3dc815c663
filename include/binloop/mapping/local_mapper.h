#pragma once
// The local mapping stage (step 2 of four; ARCHITECTURE.md): keyframes from tracking in; a LocalMapUpdate
// back to tracking and the refined keyframe on to the loop stages out. It owns the map: every keyframe and
// map point with its observations, the covisibility graph and the spanning tree. Other stages only ever see
// copies of parts of it, in messages.
//
// Threads: not thread-safe. One thread at a time calls everything, except abortFlag(), which any thread may
// set. The background global BA runs on a thread of its own over a copy of the map and touches nothing of
// the mapper's; its result is folded in only by mergeGlobalBa(), on the caller's thread.
#include <atomic>
#include <deque>
#include <map>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "binloop/features/stereo_matcher.h"
#include "binloop/map/correction_history.h"
#include "binloop/map/ids.h"
#include "binloop/map/keypoint_grid.h"
#include "binloop/map/map_store.h"
#include "binloop/map/scale_pyramid.h"
#include "binloop/mapping/epipolar_matcher.h"
#include "binloop/mapping/triangulation.h"
#include "binloop/messages/correction.h"
#include "binloop/messages/keyframe.h"
#include "binloop/messages/local_map_update.h"
#include "binloop/optim/local_bundle_adjustment.h"

namespace binloop {

class StateWriter;
class StateReader;

struct LocalMapperParams {
  int covisibility_min = 15;     // shared points for an edge of the covisibility graph
  int cull_after_keyframes = 2;  // a new point is judged this many keyframes after its creation...
  int cull_min_observers = 4;    // ... and culled if its sightings count fewer
  // How a keyframe's sighting counts there. kKeyframes: once. kStereoTwice: twice when in both images
  // (ORB-SLAM2's count; with its bound, 4, two stereo sightings keep a point). kCloseStereoTwice: twice only
  // when in both images at close depth (isCloseDepth with `stereo`), so a far point is judged by its count
  // of keyframes.
  enum class CullCount { kKeyframes, kStereoTwice, kCloseStereoTwice };
  CullCount cull_count = CullCount::kCloseStereoTwice;
  bool triangulate = true;         // new points from keypoints matched with covisible keyframes
  int triangulate_neighbors = 10;  // strongest covisible keyframes searched (ORB-SLAM2)
  EpipolarParams epipolar;
  TriangulationParams triangulation;
  bool fuse = true;           // merge duplicates with neighbouring keyframes
  int fuse_neighbors = 10;    // first-order neighbours searched (plus 5 of each one's neighbours)
  float fuse_radius = 3;      // level-0 px at level 0
  int fuse_max_hamming = 50;  // ORB-SLAM2's TH_LOW
  bool local_ba = true;
  int local_ba_max_keyframes = 30;  // optimised keyframes (the new one and its strongest neighbours)
  // A keyframe waiting cuts the running local BA short (ORB-SLAM2's abort flag; threaded only). False: it
  // runs its iterations out and the keyframe waits, so the map no longer depends on when keyframes arrive.
  bool local_ba_yields = true;
  LocalBaParams ba;
  bool cull_keyframes = true;
  // After a loop correction, a bundle adjustment of the whole map. On by default
  // (docs/results/2026-11-26-slam-measurements.md, "Loop closing, measured": what it costs and gives).
  bool global_ba_after_loop = true;
  // Its iterations (`ba` holds local BA's): with Huber loss over every observation, then plain squares
  // over the inliers.
  int global_ba_robust_iterations = 5;
  int global_ba_refine_iterations = 10;
  // Where it runs. False: on mapping's thread, before the corrected map goes to tracking (mapping waits;
  // lock-step runs stay bit-identical). True (the threaded pipeline and the nodelet set it): on its own
  // thread over a copy of the map, as ORB-SLAM2 does; mapping goes on, and mergeGlobalBa() folds the result
  // in, moving keyframes added meanwhile with their spanning-tree ancestor. A new correction stops it.
  bool global_ba_in_background = false;
  float redundant_ratio = 0.9f;  // a keyframe whose points are this often seen by >= 3 others goes
  // The tracker's stereo settings (SlamConfig copies them): which keypoints are close (culling) and whether
  // BA takes far keypoints' disparity as a measurement (`far_disparity`).
  StereoMatchParams stereo;
};

class LocalMapper {
 public:
  struct Output {
    msg::LocalMapUpdatePtr update;  // to tracking
    msg::KeyFramePtr refined;       // to the loop stages (revision 1, covisibility filled in)
  };

  explicit LocalMapper(const LocalMapperParams& p = {});
  ~LocalMapper();
  LocalMapper(const LocalMapper&) = delete;
  LocalMapper& operator=(const LocalMapper&) = delete;
  /// Inserts the keyframe and runs the local-mapping steps on it. Never throws for a keyframe that names
  /// unknown points (they are dropped); throws std::invalid_argument for a malformed message (sizes differ).
  Output process(const msg::KeyFrame& kf);
  /// A loop correction (messages/correction.h): keyframes and points move, the loop's points merge. Returns
  /// the update for tracking: the whole corrected map. Null for a correction already applied (loop closing
  /// sends one again when it thinks it lost: loop/correction_outbox.h). Throws std::invalid_argument for a
  /// correction that skips one (it comes again after the missing one).
  msg::LocalMapUpdatePtr apply(const msg::Correction& c);
  uint64_t correctionsApplied() const { return history_.applied(); }

  /// A background global BA's result folded into the map, or null while none is done (with `wait`, waits
  /// for a running one). The update carries the whole map, as after a correction.
  msg::LocalMapUpdatePtr mergeGlobalBa(bool wait = false);
  struct GlobalBaStats {
    int started = 0, merged = 0, aborted = 0;  // aborted: stopped by a correction (or discarded at the end)
    int failed = 0;                            // threw in its thread: the map stays as it was
    // Run in the foreground and stopped early by a waiting keyframe (its result is kept). SlamPipeline never
    // gets here: threaded it runs the BA in the background, lock-step no keyframe waits.
    int cut_short = 0;
    std::string last_failure;
    // The last global BA that reached the map (merged, or run in the foreground)
    BaSummary last;
    int last_keyframes = 0, last_added_meanwhile = 0;
  };
  const GlobalBaStats& globalBaStats() const { return global_ba_; }
  struct LocalBaStats {
    int runs = 0, cut_short = 0;  // cut_short: stopped early by a waiting keyframe
  };
  const LocalBaStats& localBaStats() const { return local_ba_; }
  /// Set from another thread to cut a running local BA (unless `local_ba_yields` is off) or foreground
  /// global BA short: a new keyframe is waiting. The caller clears it before each process() and apply();
  /// left set, it cuts the next one short.
  std::atomic<bool>& abortFlag() { return abort_; }

  struct KeyframePose {
    SlamKeyframeId id;
    uint64_t frame_index;
    double stamp_s;
    Pose3 T_w_c;
  };
  /// The keyframes in the map now, by id.
  std::vector<KeyframePose> keyframes() const;
  /// A keyframe's pose now; a culled keyframe's follows its parent's (it keeps its pose relative to it).
  /// False for an id never seen.
  bool keyframePose(SlamKeyframeId id, Pose3* T_w_c) const;

  /// Every map point's position now (for display).
  std::vector<Eigen::Vector3d> pointPositions() const;
  size_t keyframeCount() const { return map_.keyframes().size(); }
  size_t pointCount() const { return map_.points().size(); }

  /// Every keyframe of the map as local mapping sends it to the loop stages, marked `resent`, in the order
  /// they came: for a loop stage that started after them (a restarted process), so that it holds the map
  /// again. Poses as they are now, corrections_seen = correctionsApplied().
  std::vector<msg::KeyFramePtr> keyframeMessages() const;
  /// The whole map as one update marked whole_map (no keyframe's processing): for a tracker that started
  /// after keyframes were made (a restarted process), to adopt (Tracker::adoptMap).
  msg::LocalMapUpdatePtr wholeMap() const;

  /// The whole map it owns (keyframes with keypoints and descriptors, points with their observations, the
  /// culled keyframes' anchors, corrections made), in id order: two saves of one map give the same bytes.
  void save(StateWriter& w) const;
  /// Into a newly made mapper. Throws DataError for a broken file.
  void load(StateReader& r);
  /// After load() of a state older than what this mapper's predecessor had done (its process restarted from
  /// an autosave): the point ids it issued after that state are unknown, so new ones start a new session.
  void resumeAfterRestart() { point_ids_.startSession(); }
  /// Point ids issued so far (IdCounter::issued).
  uint64_t pointIdsIssued() const { return point_ids_.issued(); }
  /// Point ids from a new session after `issued` and after this mapper's own: for a mapper that takes
  /// another's place (a reset, a loaded map) while points of the other may still be on their way.
  void continueIdsInNewSession(uint64_t issued) { point_ids_.startSessionAfter(issued); }

 private:
  struct KF {
    msg::KeyframeState state;
    uint64_t frame_index = 0, seq = 0;
    double stamp_s = 0;
    std::vector<msg::KeyPoint> keypoints;
    Descriptors descriptors;
    KeypointGrid grid;
    std::map<SlamKeyframeId, int> weights;  // every keyframe sharing a point, with the count
  };
  struct MP {
    msg::MapPoint state;
    std::map<SlamKeyframeId, int> obs;  // keyframe -> keypoint index
    uint64_t first_seq = 0;
  };

  void insert(const msg::KeyFrame& kf);
  /// `kf` as a keyframe message at revision 1, in the map's current (corrected) frame.
  std::shared_ptr<msg::KeyFrame> messageOf(const KF& kf) const;
  void updateConnections(KF& kf);
  void cullRecentPoints(msg::LocalMapUpdate& u);
  void createNewPoints(KF& kf, msg::LocalMapUpdate& u);
  void fuseWithNeighbors(KF& kf, msg::LocalMapUpdate& u);
  /// Projects `points` into keyframe `t`; a match either adds an observation or merges two points.
  void fuseInto(KF& t, const std::vector<MapPointId>& points, msg::LocalMapUpdate& u);
  std::vector<MapPointId> pointsOf(const std::vector<SlamKeyframeId>& keyframes) const;
  void localBundleAdjustment(KF& kf, msg::LocalMapUpdate& u);
  /// Bundle adjustment of the `free` keyframes and every point they see; other keyframes that see those
  /// points hold still; `abort`, when set meanwhile, stops it early. Returns the solver's report (its points
  /// and keyframes are in the map already).
  LocalBaResult bundleAdjust(const std::vector<SlamKeyframeId>& free, const LocalBaParams& params,
                             std::atomic<bool>* abort, msg::LocalMapUpdate& u);
  struct BaSetup {
    BaProblem problem;
    size_t free = 0;  // the first `free` keyframes of the problem are optimised
    std::vector<std::pair<MapPointId, SlamKeyframeId>> obs_of;  // per observation
  };
  BaSetup makeBaProblem(const std::vector<SlamKeyframeId>& free) const;
  void removeBaOutliers(const BaSetup& b, const LocalBaResult& r, msg::LocalMapUpdate& u);
  LocalBaParams globalBaParams() const;
  void noteGlobalBa(const LocalBaResult& r, size_t keyframes);  // into global_ba_'s last* fields
  /// A point's sightings as culling counts them (`cull_count`: keyframes, or a stereo or close-stereo
  /// sighting twice).
  int observerCount(const MP& mp) const;
  /// What the update reports of the BA it carries (time, iterations, outliers).
  static void reportBa(const BaSummary& s, msg::LocalMapUpdate& u);
  /// Moves every keyframe by its delta (T_w_c_after T_w_c_before^-1) or its nearest ancestor's, and every
  /// point with its reference keyframe unless `placed` gives its new position. Returns each keyframe's
  /// delta, by id.
  std::vector<std::pair<SlamKeyframeId, Pose3>> moveMap(
      const std::unordered_map<SlamKeyframeId, Pose3>& delta,
      const std::unordered_map<MapPointId, Eigen::Vector3d>* placed);
  void wholeMapInto(msg::LocalMapUpdate& u) const;
  struct GlobalBaJob;
  void startGlobalBa(const std::vector<SlamKeyframeId>& keyframes);
  void stopGlobalBa();
  void cullKeyframes(KF& kf, msg::LocalMapUpdate& u);
  void updatePointShape(MP& mp);
  void addObservation(MP& mp, KF& kf, int idx);
  void removePoint(MapPointId id);
  void replacePoint(MapPointId removed, MapPointId kept, msg::LocalMapUpdate& u);
  void removeKeyframe(SlamKeyframeId id);
  std::vector<SlamKeyframeId> neighbors(const KF& kf, int n) const;
  MapPointId resolve(MapPointId id) const;
  /// What a message sent now has seen: both counts together, so that they never drift apart.
  template <class Message>
  void stampSeen(Message& m) const {
    m.corrections_seen = history_.applied();
    m.merges_seen = merges_.applied();
  }

  LocalMapperParams p_;
  ScalePyramid scales_;
  StereoCamera camera_;
  MapStore<KF, MP> map_;
  std::deque<MapPointId> recent_;
  std::vector<MapPointId> touched_;  // points whose state goes into this update
  std::atomic<bool> abort_{false};
  LocalBaStats local_ba_;
  IdCounter point_ids_{IdIssuer::kLocalMapping};
  uint64_t seq_ = 0, updates_ = 0;
  SlamKeyframeId first_kf_ = kNoId;
  CorrectionHistory history_;
  // What each global BA merge did to each keyframe, for keyframes tracking made before the merge reached it
  // (KeyFrame::merges_seen). Not saved: a loaded or resumed map counts merges from 0, as tracking then does.
  CorrectionHistory merges_;
  std::unique_ptr<GlobalBaJob> gba_;
  GlobalBaStats global_ba_;
};

}  // namespace binloop
