#pragma once
// The tracking stage (step 1 of four; ARCHITECTURE.md): stereo frames in, a pose per frame and keyframes out.
// It owns its state: the last frame, the motion model, and a MapReplica built only from the keyframes it
// made and the LocalMapUpdate messages it is given (loop corrections arrive as one). It never waits for
// another stage, so the pipeline can run it in lock-step or on its own thread.
#include <memory>
#include <optional>
#include <string>
#include <unordered_set>

#include "binloop/map/map_replica.h"
#include "binloop/messages/tracked_frame.h"
#include "binloop/optim/pnp_ransac.h"
#include "binloop/optim/pose_optimizer.h"
#include "binloop/tracking/far_keyframe_pose.h"
#include "binloop/tracking/frame.h"
#include "binloop/tracking/keyframe_database.h"
#include "binloop/tracking/motion_reach.h"
#include "binloop/tracking/projection_search.h"
#include "binloop/tracking/rotation_search.h"

namespace binloop {

class StateWriter;
class StateReader;

struct TrackerParams {
  OrbSlamParams orb;
  StereoMatchParams stereo;
  ProjectionParams projection;
  PoseOptimizerParams pose;
  int init_min_stereo = 500;        // stereo matches the first frame needs to become the first keyframe
  float last_frame_radius = 7;      // search radius (level-0 px at level 0) from the last frame; doubled once
  int min_last_frame_matches = 20;  // below this the wider search is tried, then the frame fails
  int motion_model_min_inliers = 50;  // fewer after the last-frame search: also try without the prediction
  float local_map_radius = 1;  // factor on the viewing-angle radius (2.5 or 4 px) in the local-map search
  float lost_radius = 5;       // the same factor while recovering after lost frames
  // After lost frames the motion model still predicts the pose for this long since the last tracked frame,
  // and recovery searches around that prediction before relocalising from scratch. A car does not stop
  // because a frame was black, and on repetitive facades a pose found without any prior can be off by one
  // facade (rendered 06: 874 inliers 2.3 m from the truth).
  double predict_through_loss_s = 3.0;
  // After this many frames lost in a row while the motion model still predicts, tracking starts again at
  // its prediction: the frame becomes a keyframe with points from its own stereo, the first of a new map
  // segment whose only tie to the old map is that prediction (its spanning-tree parent, in the pose graph)
  // until a loop joins the two. After 20 missing frames (11-30 m) the map holds too little of the view to
  // be found again from half the places of rendered 06, and without this tracking stayed lost for good.
  // 0: stay lost until relocalised.
  int restart_after_lost = 3;
  // A pose recovered while the motion model still predicts must be one the camera could have reached: within
  // recovery_min_gate_m + 1/2 a dt^2 of the prediction (a = recovery_max_accel_mps2, dt since the last
  // tracked frame); farther, the frame stays lost. A road whose texture repeated every 8 m let rendered 06
  // relocalise 24 m and 40 m behind the truth after 10 and 20 missing frames, and the next keyframes then
  // mapped there.
  double recovery_min_gate_m = 1.0;
  double recovery_max_accel_mps2 = 5.0;
  int min_inliers = 30;  // a frame is tracked with at least this many inliers after the local map
  int min_inliers_after_loss = 50;
  int max_local_keyframes = 80;
  // relocalisation when lost: descriptor matches to the points of recent keyframes, PnP RANSAC, pose
  // optimisation, then the local map
  int reloc_keyframes = 10;  // keyframes tried: those the vocabulary finds most alike, else the most recent
  /// The hbow vocabulary that indexes tracking's keyframes for relocalisation anywhere in the map; without
  /// one, only the most recent keyframes are tried.
  std::shared_ptr<const VocabularyTree> vocabulary;
  /// Which vocabulary that is (model_files.h, modelFileIdentity), checked when a saved map is loaded.
  std::string vocabulary_identity;
  int reloc_min_matches = 15;  // descriptor matches a keyframe needs before PnP is tried
  // While the motion model predicts, recovery finds the rotation from far points first, then the pose from
  // the frame's stereo against the keyframes' sightings (Tracker::recoverRotationFirst); off, it goes
  // straight from the wide search to relocalisation.
  bool recover_rotation_first = true;
  RotationSearchParams rotation_search;
  FarPoseParams far_pose;
  PnpRansacParams pnp;
  uint64_t seed = 1;                // for the RANSAC samples
  int covisible_per_keyframe = 10;  // neighbours each local keyframe adds to the local map
  // keyframe decision, ORB-SLAM2's stereo rules
  int keyframe_max_frames = 10;      // always insert after this many frames (the camera's rate)
  float keyframe_ref_ratio = 0.75f;  // insert when tracked points < this times the reference keyframe's
  int keyframe_ref_min_observers =
      2;  // ... counting its points that this many keyframes see (ORB-SLAM2: 3;
          // 2 halved the ATE on rendered 05: with 3, turns thinned the map first)
  int keyframe_close_tracked_max = 100;   // ... or fewer close points tracked than this
  int keyframe_close_untracked_min = 70;  // ... while at least this many close points could be added
  // ... or the camera turned more than this since the last keyframe (degrees; 0: no such rule). In a sharp
  // turn the view sweeps past far points in a few frames; keyframes by turn see each of them often enough to
  // keep it, and far points are what holds the rotation there.
  double keyframe_max_turn_deg = 0;
  int max_mapping_queue = 3;  // while mapping is busy, insert only if its queue is shorter
  int new_points_min = 100;   // a keyframe makes at least this many new points (closest first)
  // ... and, when true, a point for every stereo match, far ones too. ORB-SLAM2 stops at the close ones and
  // leaves far points to triangulation over keyframes; on rendered 06 making them here (their depth is then
  // refined by local BA) took t_rel from 1.14 % to 0.36 % and r_rel from 0.57 to 0.14 deg/100 m, because far
  // points are what pins the rotation.
  bool create_far_points = true;
  // Localisation only: the tracker finds its frames in the map it holds (a loaded one) and makes no
  // keyframe, so the map stays as it is (no mapping, no loop closing needed). Without a map no frame is
  // tracked; beyond the map's edge tracking runs out of points and is lost until the map is seen again.
  bool localize_only = false;
  // ... where a frame tracks fewer inliers than this, it is relocalised too and the pose that explains more
  // of the map wins: with no keyframes added, the local map never moves on to another part of the map that
  // shows the same place (a revisit the map never closed), and only relocalisation finds it.
  int localize_relocalize_below = 150;
  // A tracked frame's pose covariance is its residuals' (optim/pose_covariance.h) times this. The residuals
  // take the map points as exact; measured against the real frame-to-frame error, that is 20.6 times too
  // confident on rendered 06 and 10.0 times on real KITTI 06 (docs/decisions.md, "odometry covariance").
  double pose_covariance_scale = 15;
};

class Tracker {
 public:
  struct Output {
    msg::TrackedFrame frame;
    msg::KeyFramePtr keyframe;  // set when the frame became a keyframe
  };

  /// Throws std::invalid_argument for a camera without positive focal length, baseline and size.
  Tracker(const StereoCamera& cam, const TrackerParams& p = {});

  /// Never throws for bad input: an unusable frame (empty, mismatched sizes, wrong encoding, time going
  /// backwards) is reported in Output::frame.problem and leaves the tracker as it was. `mapping_queue` is the
  /// number of keyframes the mapper has not finished (0 = idle).
  Output track(const StereoFrame& in, int mapping_queue = 0);

  void apply(const msg::LocalMapUpdate& u);

  /// The clock started again (a bag played again, simulated time reset): the next frame may come earlier
  /// than the last. The map stays; the motion model goes, and the next frame is searched for around the last
  /// keyframe and then relocalised anywhere, as after a load. Before the first frame it changes nothing.
  void restartClock();

  /// Someone knows where the camera is (an operator's 2D Pose Estimate in rviz, a robot's own fix): while
  /// tracking is lost, the next frames are searched for within `radius_m` of `T_w_c` (map frame) first, the
  /// keyframes nearest it are tried by relocalisation, and a pose found elsewhere is refused. The hint holds
  /// until a frame is tracked (or `frames` frames have been tried); a tracker that is not lost ignores it.
  void hintPose(const Pose3& T_w_c, double radius_m, int frames = 50);

  msg::TrackingState state() const { return state_; }
  const MapReplica& map() const { return map_; }
  const TrackerParams& params() const { return p_; }
  const StereoCamera& camera() const { return cam_; }
  /// The last frame tracked (its keypoints and the map point each matched), null before the first; for
  /// display (the ROS debug image).
  const Frame* lastFrame() const { return last_.get(); }

  /// Its map replica, the ids it issued, the corrections it applied and its relocalisation index, with the
  /// camera, the extractor settings and the vocabulary they depend on.
  void save(StateWriter& w) const;
  /// Into a newly made tracker (same camera, extractor settings and vocabulary, else DataError naming both).
  /// It then starts lost: the next frame is relocalised in the loaded map.
  void load(StateReader& r);
  /// The map local mapping holds (a whole_map update), into a tracker that has not started: a tracking
  /// process restarted while the graph kept its map. Like a load, it then starts lost at the map's last
  /// keyframe, and its ids go on after the highest it finds of its own in the map. Throws
  /// std::invalid_argument once tracking has started.
  void adoptMap(const msg::LocalMapUpdate& whole);
  /// Whether local mapping's map `whole` should take this tracker's place: always before tracking started;
  /// after, only while this tracker's own map is that young (at most 2 keyframes, fewer than `whole`'s) —
  /// a pair that reached a restarted tracking before the map did began a new map, which gives way.
  bool givesWayTo(const msg::LocalMapUpdate& whole) const;
  /// Keyframe and point ids issued so far (IdCounter::issued).
  uint64_t keyframeIdsIssued() const { return keyframe_ids_.issued(); }
  uint64_t pointIdsIssued() const { return point_ids_.issued(); }
  /// Ids from a new session (IdCounter::startSession) after `keyframes` / `points` issued, or after this
  /// tracker's own if higher: a tracker that takes another's place (a reset, a loaded map) issues none of
  /// the ids its predecessor issued, which messages in flight and the other stages may still hold.
  void continueIdsInNewSession(uint64_t keyframes, uint64_t points);
  /// The camera a saved tracking state was made with, to make the tracker that loads it.
  static StereoCamera savedCamera(const std::string& path);

 private:
  /// Where the frame is expected: the motion model's prediction (or a pose hint while lost) and how far from
  /// it the camera could have got (`reach`).
  struct Prediction {
    Pose3 last_pose, T_w_c;
    double dt = 0;             // since the last tracked frame
    bool last_stale = false;   // dt is beyond the motion model's reach (predict_through_loss_s)
    bool from_motion = false;  // the motion model predicts (else the last pose stands in)
    bool hinted = false;       // a pose hint stands in
    MotionReach reach;
  };
  Prediction predict(const Frame& f) const;
  /// A frame after initialisation: tracked from the last frame, else recovered (recover()); on success the
  /// covariance, the motion model and maybe a keyframe. False: lost (out->frame says why).
  bool trackInMap(Frame& f, int mapping_queue, Output* out);
  /// Tracking as usual: the motion model, and matching without a prediction when it is missing or weak.
  bool trackFromLastFrame(Frame& f, Prediction& pred);
  /// After a failure: the reference's local map searched wide, the rotation from far points, relocalisation.
  bool recover(Frame& f, Prediction& pred, bool* relocalized);
  /// Localisation only, tracked on little of the map: relocalised too; true when that pose won.
  bool relocalizeAsWell(Frame& f);
  bool initialize(Frame& f, msg::KeyFramePtr* kf);
  bool trackLastFrame(Frame& f);
  bool trackWithoutPrediction(Frame& f);
  bool poseFromMatches(Frame& f, int matches);
  /// Frames were lost and the prediction is off in rotation: the rotation from far points
  /// (rotation_search.h), then the pose from the frame's stereo and the keyframes' sightings
  /// (far_keyframe_pose.h). Leaves f.T_w_c and its inlier matches; false when either step fails.
  bool recoverRotationFirst(Frame& f, const Pose3& predicted);
  /// The points of these keyframes, each once, leaving out those in `skip` (ids as resolved).
  std::vector<const msg::MapPoint*> pointsOf(const std::vector<SlamKeyframeId>& keyframes,
                                             const std::unordered_set<MapPointId>& skip = {}) const;
  /// `pts` projected at f.T_w_c and matched to f's free keypoints within `radius`; the number matched.
  int searchByProjection(Frame& f, const std::vector<const msg::MapPoint*>& pts, float radius) const;
  /// The frame's matched keypoints with stereo depth, each with up to three of its point's keyframes
  /// (sightingKeyframes).
  std::vector<FarMatch> farMatches(const Frame& f, std::vector<int>* keypoint_of) const;
  /// Which of a point's observers farMatches uses, whatever order the replica lists them in.
  std::vector<SlamKeyframeId> sightingKeyframes(const msg::MapPoint& mp) const;
  /// Lost at the map's last keyframe, with no motion model (after a load or an adopted map).
  void startLostAtLastKeyframe();
  /// Relocalisation from scratch against the vocabulary's (or the most recent) keyframes: the candidate
  /// that explains most of the local map among those the camera could have reached (`reach`); with
  /// `hinted`, the keyframes nearest the pose hint are tried first.
  bool relocalize(Frame& f, MotionReach& reach, bool hinted);
  /// PnP RANSAC on the matches in f.points, pose optimisation, a wide search for `pts`, then the local map.
  bool poseFromScratch(Frame& f, const std::vector<const msg::MapPoint*>& pts);
  bool trackLocalMap(Frame& f, float radius, int min_inliers);
  int optimizePose(Frame& f);
  /// The frame's matched map points as pose-optimisation observations (`index`: their keypoints); a match
  /// whose point the replica no longer holds is dropped from the frame.
  std::vector<PoseObservation> observationsOf(Frame& f, std::vector<int>* index) const;
  void updateLocalKeyframes(const Frame& f);
  /// The reference keyframe's points seen by enough keyframes to count (ORB-SLAM2's nRefMatches).
  int referencePoints() const;
  /// ORB-SLAM2's keyframe rule; `found_again`: the frame was found near the prediction after lost frames,
  /// which makes a keyframe whatever the rule says.
  bool needKeyframe(const Frame& f, int mapping_queue, int reference_points, bool found_again) const;
  /// The camera turned more than keyframe_max_turn_deg since the last keyframe.
  bool turned(const Frame& f) const;
  /// Tracking's fresh start at the prediction (`restart_after_lost`), when its conditions hold.
  bool restartAtPrediction(Frame& f, const Prediction& pred, Output* out);
  msg::KeyFramePtr makeKeyframe(Frame& f);
  Pose3 lastPose() const;

  StereoCamera cam_;
  TrackerParams p_;
  FrameBuilder builder_;
  MapReplica map_;
  IdCounter keyframe_ids_{IdIssuer::kTracking};
  IdCounter point_ids_{IdIssuer::kTracking};
  msg::TrackingState state_ = msg::TrackingState::kNotInitialized;
  std::unique_ptr<Frame> last_;
  SlamKeyframeId last_ref_ = kNoId;     // the last frame's pose is kept relative to this keyframe, so that
  Pose3 T_ref_last_;                    // local BA moving that keyframe moves the last frame too
  Pose3 velocity_ = Pose3::Identity();  // T_prev_last
  double velocity_dt_ = 1;              // seconds between those two frames
  bool have_velocity_ = false;
  double last_stamp_ = 0;
  bool have_stamp_ = false;
  SlamKeyframeId reference_ = kNoId;
  struct LastKeyframe {
    uint64_t frame = 0;  // the frame it was made from
    SlamKeyframeId id = kNoId;
    Eigen::Matrix3d R_w_c = Eigen::Matrix3d::Identity();  // as tracked, for when the map lacks it
  };
  LastKeyframe last_keyframe_;  // the last one this tracker made
  std::vector<SlamKeyframeId> local_keyframes_;
  int inliers_ = 0;
  int lost_in_a_row_ = 0;
  bool restarted_ = false;  // restarted at a prediction, and no frame tracked since
  uint64_t reloc_attempts_ = 0;
  uint64_t corrections_seen_ = 0;  // loop corrections applied (through local mapping's updates)
  uint64_t merges_seen_ = 0;       // global BA results merged, as the mapper last counted them
  std::unique_ptr<KeyframeDatabase> keyframe_db_;  // with a vocabulary only
  struct PoseHint {
    Pose3 T_w_c;
    double radius_m = 0;
    int frames_left = 0;
  };
  std::optional<PoseHint> hint_;  // hintPose()
};

}  // namespace binloop
