#include "binloop/tracking/tracker.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <unordered_map>
#include <unordered_set>

#include "binloop/io/data_error.h"
#include "binloop/map/keypoint_geometry.h"
#include "binloop/optim/pose_covariance.h"
#include "binloop/util/fixed_decimals.h"
#include "binloop/util/hash_random.h"
#include "binloop/util/stopwatch.h"

namespace binloop {

namespace {

// The motion T repeated k times (k need not be whole): rotation angle and translation scaled by k, which is
// exact for k = 1 and close for the small motions between frames.
Pose3 scaledMotion(const Pose3& T, double k) {
  if (!(k > 0) || std::abs(k - 1) < 1e-9) return T;
  const Eigen::AngleAxisd aa(T.linear());
  Pose3 out = Pose3::Identity();
  out.linear() = Eigen::AngleAxisd(aa.angle() * k, aa.axis()).toRotationMatrix();
  out.translation() = T.translation() * k;
  return out;
}

}  // namespace

const char* msg::toString(TrackingState s) {
  switch (s) {
    case TrackingState::kNotInitialized:
      return "not initialized";
    case TrackingState::kOk:
      return "ok";
    case TrackingState::kLost:
      return "lost";
    case TrackingState::kRelocalized:
      return "relocalized";
  }
  return "?";
}

Tracker::Tracker(const StereoCamera& cam, const TrackerParams& p)
    : cam_(cam), p_(p), builder_(cam, p.orb, p.stereo) {
  if (p_.vocabulary) keyframe_db_ = std::make_unique<KeyframeDatabase>(p_.vocabulary);
}

Pose3 Tracker::lastPose() const {
  if (const msg::KeyframeState* ref = map_.keyframe(last_ref_))
    return orthonormalized(ref->T_w_c * T_ref_last_);
  return last_->T_w_c;
}

Tracker::Output Tracker::track(const StereoFrame& in, int mapping_queue) {
  Output out;
  msg::TrackedFrame& tf = out.frame;
  tf.frame_index = static_cast<uint64_t>(in.index);
  tf.stamp_s = in.stamp_s;
  tf.state = state_ == msg::TrackingState::kNotInitialized ? state_ : msg::TrackingState::kLost;
  if (last_) tf.T_w_c = lastPose();
  tf.reference = reference_;

  if (have_stamp_ && !(in.stamp_s > last_stamp_)) {
    tf.problem = "frame " + std::to_string(in.index) + ": time " + std::to_string(in.stamp_s) +
                 " s does not come after the last frame's " + std::to_string(last_stamp_) +
                 " s; frame skipped";
    return out;
  }
  Frame f;
  try {
    f = builder_.build(in);
  } catch (const std::exception& e) {
    tf.problem = std::string(e.what()) + "; frame skipped";
    return out;
  }
  have_stamp_ = true;
  last_stamp_ = in.stamp_s;
  tf.features = static_cast<int>(f.size());
  tf.stereo_matches = f.stereo_matches;
  tf.extract_ms = f.extract_ms;
  tf.stereo_ms = f.stereo_ms;
  const auto t0 = std::chrono::steady_clock::now();

  if (state_ == msg::TrackingState::kNotInitialized) {
    if (p_.localize_only) {
      tf.problem = "localisation only, and no map to localise in: load one";
      tf.track_ms = msSince(t0);
      return out;
    }
    if (!initialize(f, &out.keyframe)) {
      tf.problem = "not initialised: " + std::to_string(f.stereo_matches) + " stereo matches, " +
                   std::to_string(p_.init_min_stereo) + " needed";
      tf.track_ms = msSince(t0);
      return out;
    }
    tf.state = state_;
  } else if (!trackInMap(f, mapping_queue, &out)) {
    tf.track_ms = msSince(t0);
    return out;
  }

  tf.T_w_c = f.T_w_c;
  tf.tracked_points = f.matchedInliers();
  tf.reference = reference_;
  if (const msg::KeyframeState* ref = map_.keyframe(reference_)) tf.T_ref_c = ref->T_w_c.inverse() * f.T_w_c;
  if (out.keyframe) tf.new_keyframe = out.keyframe->id;
  last_ref_ = reference_;
  T_ref_last_ = tf.T_ref_c;
  last_ = std::make_unique<Frame>(std::move(f));
  tf.track_ms = msSince(t0);
  return out;
}

Tracker::Prediction Tracker::predict(const Frame& f) const {
  Prediction p;
  p.last_pose = lastPose();
  // The motion model over the time since the last tracked frame, so that frames lost in between (a dropped
  // message, a skipped bad image) do not leave the prediction behind.
  p.dt = f.stamp_s - last_->stamp_s;
  p.last_stale = p.dt > p_.predict_through_loss_s;
  p.from_motion = have_velocity_ && !p.last_stale;
  // A pose hint while lost stands in for the prediction: the frame is searched for there and must be found
  // within its radius.
  p.hinted = hint_ && state_ == msg::TrackingState::kLost;
  p.T_w_c = p.hinted        ? hint_->T_w_c
            : p.from_motion ? orthonormalized(p.last_pose * scaledMotion(velocity_, p.dt / velocity_dt_))
                            : p.last_pose;
  if (p.hinted) {
    p.reach = MotionReach(p.T_w_c.translation(), hint_->radius_m, 0, 0);
  } else if (p.from_motion) {
    p.reach = MotionReach(p.T_w_c.translation(), p_.recovery_min_gate_m, p_.recovery_max_accel_mps2, p.dt);
  }
  return p;
}

bool Tracker::trackInMap(Frame& f, int mapping_queue, Output* out) {
  msg::TrackedFrame& tf = out->frame;
  Prediction pred = predict(f);
  f.T_w_c = pred.T_w_c;
  // A last frame older than the motion model reaches (the camera may have been carried anywhere meanwhile)
  // is not matched against: on a road whose texture repeats it lent a frame 100 m away 30 chance inliers.
  bool ok = state_ == msg::TrackingState::kOk && !pred.last_stale && trackFromLastFrame(f, pred);
  bool relocalized = false;  // found from scratch, not near the prediction
  if (!ok) ok = recover(f, pred, &relocalized);
  if (ok && p_.localize_only && !relocalized && inliers_ < p_.localize_relocalize_below)
    relocalized = relocalizeAsWell(f);
  if (pred.hinted && (ok || --hint_->frames_left <= 0)) hint_.reset();
  // Frames searched near a pose hint do not count: when the hint runs out, the operator's pose had its go.
  lost_in_a_row_ = ok || pred.hinted ? 0 : lost_in_a_row_ + 1;
  if (ok) restarted_ = false;
  if (!ok && restartAtPrediction(f, pred, out)) return true;
  if (!ok) {
    state_ = msg::TrackingState::kLost;
    tf.state = state_;
    tf.problem = "lost: " + std::to_string(inliers_) + " inliers";
    const MotionReach& reach = pred.reach;
    if (reach.nearestRefusedM() >= 0) {
      tf.problem +=
          "; a pose " + fixedDecimals(reach.nearestRefusedM(), 1) + " m from the " +
          (pred.hinted ? std::string("pose hint")
                       : "motion model's prediction after " + fixedDecimals(reach.dtS(), 1) + " s") +
          " was rejected (at most " + fixedDecimals(reach.radiusM(), 1) + " m)";
    }
    tf.T_w_c = pred.T_w_c;  // not what a failed attempt left in f
    return false;
  }
  tf.state = state_ == msg::TrackingState::kRelocalized ? state_ : msg::TrackingState::kOk;
  state_ = msg::TrackingState::kOk;
  // Every match left after the last pose optimisation is one of its inliers.
  const PoseCovariance cov = poseCovariance(cam_, f.T_w_c, observationsOf(f, nullptr));
  if (cov.valid) tf.pose_covariance = p_.pose_covariance_scale * cov.covariance;
  // The motion from the last tracked frame is the velocity, unless the frame was found from scratch: then
  // that "motion" is wherever the camera was carried, and the next frame is matched without a prediction
  // (as ORB-SLAM2 drops its velocity after relocalising).
  velocity_ = pred.last_pose.inverse() * f.T_w_c;
  velocity_dt_ = pred.dt > 0 ? pred.dt : 1;
  have_velocity_ = !relocalized;
  tf.mapping_queue = mapping_queue;
  if (!p_.localize_only) {  // a map that stays as loaded needs no keyframe decision
    tf.reference_points = referencePoints();
    const bool found_again = tf.state == msg::TrackingState::kRelocalized && !relocalized;
    if (needKeyframe(f, mapping_queue, tf.reference_points, found_again)) out->keyframe = makeKeyframe(f);
  }
  return true;
}

bool Tracker::restartAtPrediction(Frame& f, const Prediction& pred, Output* out) {
  // One restart until a frame is tracked again: a restarted frame resets the prediction's clock, and a
  // camera that keeps failing would otherwise be dead-reckoned segment after segment for ever.
  if (p_.restart_after_lost <= 0 || lost_in_a_row_ < p_.restart_after_lost || restarted_ ||
      !pred.from_motion || pred.hinted || p_.localize_only || f.stereo_matches < p_.init_min_stereo)
    return false;
  const int lost = lost_in_a_row_;
  f.clearMatches();
  f.T_w_c = pred.T_w_c;
  reference_ = last_ref_;  // the new keyframe's parent: the old map's keyframe the prediction came from
  out->keyframe = makeKeyframe(f);
  local_keyframes_ = {reference_};
  inliers_ = 0;
  lost_in_a_row_ = 0;
  restarted_ = true;
  state_ = msg::TrackingState::kOk;
  // The velocity stays: the car is still moving as it was predicted to.
  msg::TrackedFrame& tf = out->frame;
  tf.state = state_;
  tf.problem = "not found in the map for " + std::to_string(lost) +
               " frames in a row: tracking started again at the motion model's prediction after " +
               fixedDecimals(pred.dt, 1) + " s, in a new map segment (keyframe " +
               std::to_string(out->keyframe->id) + ") tied to the old one by that prediction alone";
  return true;
}

bool Tracker::trackFromLastFrame(Frame& f, Prediction& pred) {
  // The motion model when there is one; without it (right after the first keyframe), when it fails, or
  // when it holds on to only a few points (in a sharp turn a wrong prediction can still collect a dozen
  // chance matches), descriptor matching against the last frame, which needs no prediction; the
  // attempt that tracks more of the local map wins.
  Frame by_model = f;
  bool model_ok = have_velocity_ && trackLastFrame(by_model);
  const bool model_strong = model_ok && inliers_ >= p_.motion_model_min_inliers;
  model_ok = model_ok && trackLocalMap(by_model, p_.local_map_radius, p_.min_inliers);
  const int model_inliers = model_ok ? inliers_ : 0;
  model_ok = model_ok && pred.reach.admits(by_model.T_w_c);
  if (model_ok && model_strong) {
    f = std::move(by_model);
    return true;
  }
  f.T_w_c = pred.T_w_c;  // matching ignores it; the pose optimisation starts there
  bool ok = trackWithoutPrediction(f) && trackLocalMap(f, p_.local_map_radius, p_.min_inliers) &&
            pred.reach.admits(f.T_w_c);
  if (model_ok && (!ok || model_inliers >= inliers_)) {
    f = std::move(by_model);
    inliers_ = model_inliers;
    ok = true;
    updateLocalKeyframes(f);  // the reference keyframe of the attempt that won
  }
  return ok;
}

bool Tracker::recover(Frame& f, Prediction& pred, bool* relocalized) {
  // Recovery: first the local map of the reference keyframe, searched wide around the prediction; then,
  // while the prediction holds, its rotation mended from far points (recoverRotationFirst()); then
  // relocalisation against recent keyframes (relocalize()).
  f.T_w_c = pred.T_w_c;
  f.clearMatches();
  local_keyframes_.clear();
  if (const msg::KeyframeState* ref = map_.keyframe(reference_)) {
    local_keyframes_.push_back(ref->id);
    for (const auto& e : ref->covisible) {
      if (static_cast<int>(local_keyframes_.size()) >= p_.covisible_per_keyframe) break;
      local_keyframes_.push_back(e.id);
    }
  }
  // Each step's pose must be one the camera could have reached (MotionReach): a road whose texture
  // repeats lets a wrong pose gather dozens of inliers.
  MotionReach& reach = pred.reach;
  const SlamKeyframeId reference_before = reference_;
  bool ok = trackLocalMap(f, p_.lost_radius, p_.min_inliers_after_loss) && reach.admits(f.T_w_c);
  if (!ok && pred.from_motion && p_.recover_rotation_first)
    ok = recoverRotationFirst(f, pred.T_w_c) && reach.admits(f.T_w_c);
  // Still nothing: the pose is unknown; find it from scratch against recent keyframes.
  // Localisation only: the map is as loaded, and two parts of it may show one place a metre apart (a
  // revisit never closed); a pose found in the other part is no less right, so no gate.
  MotionReach anywhere;
  if (!ok)
    ok = *relocalized = relocalize(f, p_.localize_only && !pred.hinted ? anywhere : reach, pred.hinted);
  if (!ok) reference_ = reference_before;
  if (ok && (*relocalized || state_ != msg::TrackingState::kOk)) state_ = msg::TrackingState::kRelocalized;
  return ok;
}

bool Tracker::relocalizeAsWell(Frame& f) {
  // Tracked, but on little of the map: relocalised as well, and the pose that explains more of it wins
  // (ORB-SLAM2's localisation mode does the same once it is down to visual odometry).
  const int tracked = inliers_;
  const std::vector<SlamKeyframeId> local = local_keyframes_;
  const SlamKeyframeId reference = reference_;
  Frame other = f;
  MotionReach anywhere;
  if (relocalize(other, anywhere, false) && inliers_ > tracked) {
    f = std::move(other);
    state_ = msg::TrackingState::kRelocalized;
    return true;
  }
  inliers_ = tracked;
  local_keyframes_ = local;
  reference_ = reference;
  return false;
}

bool Tracker::initialize(Frame& f, msg::KeyFramePtr* kf) {
  if (f.stereo_matches < p_.init_min_stereo) return false;
  f.T_w_c = Pose3::Identity();
  *kf = makeKeyframe(f);
  state_ = msg::TrackingState::kOk;
  return true;
}

std::vector<PoseObservation> Tracker::observationsOf(Frame& f, std::vector<int>* index) const {
  std::vector<PoseObservation> obs;
  const ScalePyramid& s = builder_.scales();
  for (size_t i = 0; i < f.size(); ++i) {
    if (f.points[i] == kNoId) continue;
    const msg::MapPoint* mp = map_.point(f.points[i]);
    if (!mp) {
      f.points[i] = kNoId;
      continue;
    }
    const msg::KeyPoint& k = f.keypoints[i];
    PoseObservation o;
    o.p_w = mp->p_w;
    o.uv = {k.x, k.y};
    o.u_right = measuredRightX(k, cam_, p_.stereo);
    o.inv_sigma2 = s.inv_sigma2[k.octave];
    obs.push_back(o);
    if (index) index->push_back(static_cast<int>(i));
  }
  return obs;
}

int Tracker::optimizePose(Frame& f) {
  std::vector<int> index;
  const std::vector<PoseObservation> obs = observationsOf(f, &index);
  if (obs.size() < 3) return 0;
  const PoseOptimizationResult r =
      binloop::optimizePose(cam_, orthonormalized(f.T_w_c.inverse()), obs, p_.pose);
  f.T_w_c = orthonormalized(r.T_c_w.inverse());
  // Every caller drops the outliers' matches, so that the next search may give those keypoints to other
  // points.
  int inliers = 0;
  for (size_t j = 0; j < index.size(); ++j) {
    if (r.outlier[j]) f.points[index[j]] = kNoId;
    inliers += !r.outlier[j];
  }
  return inliers;
}

bool Tracker::trackLastFrame(Frame& f) {
  auto lookup = [this](MapPointId id) { return map_.point(id); };
  // The last frame's pose as local BA now has it.
  Frame& last = *last_;
  last.T_w_c = lastPose();
  int n = matchFromLastFrame(f, last, lookup, cam_, builder_.scales(), p_.last_frame_radius, p_.projection);
  if (n < p_.min_last_frame_matches) {
    std::fill(f.points.begin(), f.points.end(), kNoId);
    n = matchFromLastFrame(f, last, lookup, cam_, builder_.scales(), 2 * p_.last_frame_radius, p_.projection);
  }
  return poseFromMatches(f, n);
}

bool Tracker::trackWithoutPrediction(Frame& f) {
  auto lookup = [this](MapPointId id) { return map_.point(id); };
  return poseFromMatches(f, matchByDescriptor(f, *last_, lookup));
}

bool Tracker::poseFromMatches(Frame& f, int matches) {
  inliers_ = matches >= p_.min_last_frame_matches ? optimizePose(f) : matches;
  return matches >= p_.min_last_frame_matches && inliers_ >= 10;
}

namespace {

// Each point's best keypoint of the whole frame, if clearly better than the second (brute force: this runs
// once per lost frame and keyframe, not per tracked frame); the matches go into f.points.
void matchPointsByDescriptor(Frame& f, const std::vector<const msg::MapPoint*>& pts) {
  for (const msg::MapPoint* mp : pts) {
    int best = 256, second = 256, best_j = -1;
    for (size_t j = 0; j < f.size(); ++j) {
      const int d = hamming(mp->descriptor, f.descriptors[j]);
      if (d < best) {
        second = best, best = d, best_j = static_cast<int>(j);
      } else if (d < second) {
        second = d;
      }
    }
    if (best_j < 0 || best > 64 || best > 0.8 * second || f.points[best_j] != kNoId) continue;
    f.points[best_j] = mp->id;
  }
}

}  // namespace

bool Tracker::poseFromScratch(Frame& f, const std::vector<const msg::MapPoint*>& pts) {
  const ScalePyramid& s = builder_.scales();
  std::vector<Eigen::Vector3d> p_w;
  std::vector<Eigen::Vector2d> uv;
  std::vector<double> w;
  std::vector<int> kp_of;
  for (size_t j = 0; j < f.size(); ++j) {
    const msg::MapPoint* mp = f.points[j] != kNoId ? map_.point(f.points[j]) : nullptr;
    if (!mp) continue;
    p_w.push_back(mp->p_w);
    uv.emplace_back(f.keypoints[j].x, f.keypoints[j].y);
    w.push_back(s.inv_sigma2[f.keypoints[j].octave]);
    kp_of.push_back(static_cast<int>(j));
  }
  if (static_cast<int>(p_w.size()) < p_.reloc_min_matches) return false;
  const PnpRansacResult r = solvePnpRansac(p_w, uv, w, cam_, p_.pnp, hashCombine(p_.seed, ++reloc_attempts_));
  if (!r.ok) return false;
  for (size_t i = 0; i < kp_of.size(); ++i)
    if (!r.inlier[i]) f.points[kp_of[i]] = kNoId;
  f.T_w_c = r.T_c_w.inverse();
  if (optimizePose(f) < 10) return false;
  // The other points, searched wide around the PnP pose (ORB-SLAM2's th = 10), then refined.
  searchByProjection(f, pts, 10);
  optimizePose(f);
  return trackLocalMap(f, p_.lost_radius, p_.min_inliers_after_loss);
}

int Tracker::searchByProjection(Frame& f, const std::vector<const msg::MapPoint*>& pts, float radius) const {
  const Pose3 T_c_w = f.T_w_c.inverse();
  std::vector<ProjectedPoint> visible;
  for (const msg::MapPoint* mp : pts) {
    ProjectedPoint pp;
    if (projectIntoFrame(*mp, T_c_w, cam_, builder_.scales(), &pp)) visible.push_back(pp);
  }
  return matchProjectedPoints(f, visible, builder_.scales(), radius, p_.projection);
}

std::vector<const msg::MapPoint*> Tracker::pointsOf(const std::vector<SlamKeyframeId>& keyframes,
                                                    const std::unordered_set<MapPointId>& skip) const {
  std::vector<const msg::MapPoint*> pts;
  std::unordered_set<MapPointId> seen;
  for (SlamKeyframeId k : keyframes) {
    const msg::KeyframeState* kf = map_.keyframe(k);
    if (!kf) continue;
    for (MapPointId id : kf->point_ids) {
      const msg::MapPoint* mp = id != kNoId ? map_.point(id) : nullptr;
      if (mp && !skip.count(mp->id) && seen.insert(mp->id).second) pts.push_back(mp);
    }
  }
  return pts;
}

std::vector<SlamKeyframeId> Tracker::sightingKeyframes(const msg::MapPoint& mp) const {
  // The three observers farthest from the point, chosen so and not by the observer lists' order. From far
  // away a keyframe fixes the point's direction and leaves its depth loose, which is what the frame's own
  // stereo knows better (far_keyframe_pose.h); the nearest observers would hold the point at depths
  // measured 30-40 m back.
  std::vector<std::pair<double, SlamKeyframeId>> by_range;
  for (SlamKeyframeId k : map_.observers(mp.id)) {
    const msg::KeyframeState* kf = map_.keyframe(k);
    if (!kf || !((kf->T_w_c.inverse() * mp.p_w).z() > 0)) continue;
    by_range.emplace_back((kf->T_w_c.translation() - mp.p_w).squaredNorm(), k);
  }
  const size_t n = std::min<size_t>(3, by_range.size());
  std::partial_sort(by_range.begin(), by_range.begin() + n, by_range.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first > b.first : a.second > b.second;
  });
  std::vector<SlamKeyframeId> ids;
  for (size_t i = 0; i < n; ++i) ids.push_back(by_range[i].second);
  return ids;
}

std::vector<FarMatch> Tracker::farMatches(const Frame& f, std::vector<int>* keypoint_of) const {
  const ScalePyramid& s = builder_.scales();
  std::vector<FarMatch> matches;
  keypoint_of->clear();
  for (size_t j = 0; j < f.size(); ++j) {
    const msg::KeyPoint& k = f.keypoints[j];
    const msg::MapPoint* mp = f.points[j] != kNoId ? map_.point(f.points[j]) : nullptr;
    if (!mp || !(k.depth > 0) || k.right_x < 0) continue;
    FarMatch m;
    m.p_w = mp->p_w;
    m.keypoint = k;
    m.inv_sigma2 = s.inv_sigma2[k.octave];
    // The keyframes' observations as the map has them after local BA: where the point projects, at the
    // level its distance predicts (the replica keeps poses and point ids, not keyframes' keypoints).
    for (const SlamKeyframeId k : sightingKeyframes(*mp)) {
      const msg::KeyframeState* kf = map_.keyframe(k);
      KeyframeSighting ks;
      ks.keyframe = k;
      ks.T_c_w = kf->T_w_c.inverse();
      const Eigen::Vector3d q = ks.T_c_w * mp->p_w;
      const Eigen::Vector3d uvr = projectStereo(q, cam_);
      ks.keypoint.x = static_cast<float>(uvr.x());
      ks.keypoint.y = static_cast<float>(uvr.y());
      ks.keypoint.right_x = static_cast<float>(uvr.z());
      ks.inv_sigma2 = s.inv_sigma2[s.predictLevel(mp->max_distance, static_cast<float>(q.norm()))];
      m.sightings.push_back(ks);
    }
    if (m.sightings.empty()) continue;
    matches.push_back(std::move(m));
    keypoint_of->push_back(static_cast<int>(j));
  }
  return matches;
}

bool Tracker::recoverRotationFirst(Frame& f, const Pose3& predicted) {
  const std::vector<SlamKeyframeId> recent = map_.recentKeyframes(static_cast<size_t>(p_.reloc_keyframes));
  const std::vector<const msg::MapPoint*> pts = pointsOf(recent);
  const ScalePyramid& s = builder_.scales();
  const RotationSearchResult r =
      searchRotation(f, predicted, pts, cam_, s, p_.rotation_search, hashCombine(p_.seed, ++reloc_attempts_));
  if (!r.ok) return false;
  f.clearMatches();
  f.T_w_c = predicted;
  f.T_w_c.linear() = predicted.linear() * r.R_pred_c;
  f.T_w_c = orthonormalized(f.T_w_c);
  searchByProjection(f, pts, p_.lost_radius);
  std::vector<int> keypoint_of;
  const std::vector<FarMatch> matches = farMatches(f, &keypoint_of);
  const std::vector<MapPointId> matched = f.points;
  std::fill(f.points.begin(), f.points.end(), kNoId);
  const FarPoseResult fp =
      farKeyframePose(cam_, matches, f.T_w_c, p_.far_pose, hashCombine(p_.seed, ++reloc_attempts_));
  if (!fp.ok) return false;
  // No pose optimisation against the map after this: it is the step that rests on the points' far-off
  // depths. The next keyframe's local BA sees these points from both sides and moves them.
  f.T_w_c = orthonormalized(fp.T_w_c);
  for (size_t i = 0; i < matches.size(); ++i)
    if (fp.inlier[i]) f.points[keypoint_of[i]] = matched[keypoint_of[i]];
  inliers_ = fp.inliers;
  updateLocalKeyframes(f);  // the reference becomes the keyframe that shares most of them
  return true;
}

void Tracker::hintPose(const Pose3& T_w_c, double radius_m, int frames) {
  if (!(radius_m > 0) || frames < 1 || !T_w_c.matrix().allFinite())
    throw std::invalid_argument("pose hint: a finite pose, a radius > 0 and at least one frame");
  if (state_ != msg::TrackingState::kLost) return;  // tracking knows better than the hint
  hint_ = PoseHint{orthonormalized(T_w_c), radius_m, frames};
}

bool Tracker::relocalize(Frame& f, MotionReach& reach, bool hinted) {
  std::unique_ptr<Frame> best;
  int best_inliers = 0;
  std::vector<SlamKeyframeId> best_local;
  SlamKeyframeId best_reference = reference_;
  const Pose3 start = f.T_w_c;
  std::vector<SlamKeyframeId> tries;
  // An empty index (a map adopted from local mapping carries no descriptors to index) finds nothing: the
  // most recent keyframes then, as without a vocabulary.
  if (keyframe_db_ && keyframe_db_->size() > 0) {
    tries = keyframe_db_->candidates(f.descriptors, static_cast<size_t>(p_.reloc_keyframes),
                                     [this](SlamKeyframeId k) {
                                       std::vector<SlamKeyframeId> n;
                                       if (const msg::KeyframeState* kf = map_.keyframe(k)) {
                                         for (const auto& e : kf->covisible)
                                           if (n.size() < 10) n.push_back(e.id);
                                       }
                                       return n;
                                     });
  } else {
    tries = map_.recentKeyframes(static_cast<size_t>(p_.reloc_keyframes));
  }
  // A hint's nearest keyframes go first (the vocabulary may not rank them: the view may have changed).
  if (hinted) {
    std::vector<SlamKeyframeId> near = map_.keyframesNear(hint_->T_w_c.translation(), hint_->radius_m,
                                                          static_cast<size_t>(p_.reloc_keyframes));
    for (SlamKeyframeId k : tries)
      if (std::find(near.begin(), near.end(), k) == near.end()) near.push_back(k);
    tries = std::move(near);
  }
  for (SlamKeyframeId k : tries) {
    if (!map_.keyframe(k)) continue;
    const std::vector<const msg::MapPoint*> pts = pointsOf({k});
    f.clearMatches();
    f.T_w_c = start;
    matchPointsByDescriptor(f, pts);
    const bool tracked = poseFromScratch(f, pts) && reach.admits(f.T_w_c);
    // Every candidate is tried and the one that explains most of the local map wins: with repeated
    // structure a wrong pose can still gather a few dozen inliers.
    if (tracked && (!best || inliers_ > best_inliers)) {
      best = std::make_unique<Frame>(f);
      best_inliers = inliers_;
      best_local = local_keyframes_;
      best_reference = reference_;
    }
  }
  if (best) {
    f = std::move(*best);
    inliers_ = best_inliers;
    local_keyframes_ = best_local;
    reference_ = best_reference;
    return true;
  }
  f.clearMatches();
  return false;
}

void Tracker::updateLocalKeyframes(const Frame& f) {
  std::unordered_map<SlamKeyframeId, int> count;
  for (size_t i = 0; i < f.size(); ++i) {
    if (f.points[i] == kNoId || f.outlier[i]) continue;
    const MapPointId id = map_.resolve(f.points[i]);
    if (id == kNoId) continue;
    for (SlamKeyframeId k : map_.observers(id)) ++count[k];
  }
  if (count.empty()) return;  // keep the previous local map
  std::vector<std::pair<int, SlamKeyframeId>> ranked;
  ranked.reserve(count.size());
  for (const auto& [k, c] : count) ranked.emplace_back(c, k);
  // Most shared points first; ties by id so that the order never depends on the hash map's.
  std::sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first > b.first : a.second > b.second;
  });
  local_keyframes_.clear();
  std::unordered_set<SlamKeyframeId> in;
  auto add = [&](SlamKeyframeId k) {
    if (k != kNoId && in.insert(k).second && map_.keyframe(k)) local_keyframes_.push_back(k);
  };
  for (const auto& [c, k] : ranked) {
    if (static_cast<int>(local_keyframes_.size()) >= p_.max_local_keyframes) break;
    add(k);
  }
  reference_ = ranked.front().second;
  const size_t direct = local_keyframes_.size();
  for (size_t i = 0; i < direct && static_cast<int>(local_keyframes_.size()) < p_.max_local_keyframes; ++i) {
    const msg::KeyframeState* kf = map_.keyframe(local_keyframes_[i]);
    int added = 0;
    for (const auto& e : kf->covisible) {
      if (added >= p_.covisible_per_keyframe) break;
      if (in.count(e.id) == 0 && map_.keyframe(e.id)) ++added;
      add(e.id);
    }
    add(kf->parent);
  }
}

bool Tracker::trackLocalMap(Frame& f, float radius, int min_inliers) {
  updateLocalKeyframes(f);
  std::unordered_set<MapPointId> have;
  for (size_t i = 0; i < f.size(); ++i)
    if (f.points[i] != kNoId) have.insert(map_.resolve(f.points[i]));
  searchByProjection(f, pointsOf(local_keyframes_, have), radius);
  inliers_ = optimizePose(f);
  return inliers_ >= min_inliers;
}

int Tracker::referencePoints() const {
  const size_t min_obs =
      std::min<size_t>(map_.keyframeCount() <= 2 ? 2 : 3, static_cast<size_t>(p_.keyframe_ref_min_observers));
  int n = 0;
  if (const msg::KeyframeState* ref = map_.keyframe(reference_)) {
    for (MapPointId id : ref->point_ids) {
      const MapPointId p = id != kNoId ? map_.resolve(id) : kNoId;
      if (p != kNoId && map_.observers(p).size() >= min_obs) ++n;
    }
  }
  return n;
}

bool Tracker::turned(const Frame& f) const {
  if (p_.keyframe_max_turn_deg <= 0) return false;
  Eigen::Matrix3d R_w_k = last_keyframe_.R_w_c;
  // As the map holds it now: a loop correction since has moved it with the frames.
  if (const msg::KeyframeState* k = map_.keyframe(last_keyframe_.id)) R_w_k = k->T_w_c.linear();
  return rotationDeg(R_w_k.transpose() * f.T_w_c.linear()) > p_.keyframe_max_turn_deg;
}

bool Tracker::needKeyframe(const Frame& f, int mapping_queue, int ref_matches, bool found_again) const {
  // A frame found again after lost frames near the prediction (not from scratch) is a keyframe even when
  // it holds too few inliers for the rule below (more than 15), and whatever the mapping queue: otherwise
  // the next frames had no points near enough to track and were lost until tracking restarted in a new
  // map segment.
  if (found_again) return true;
  if (mapping_queue >= p_.max_mapping_queue) return false;
  const size_t kfs = map_.keyframeCount();
  int tracked_close = 0, untracked_close = 0;
  for (size_t i = 0; i < f.size(); ++i) {
    const float d = f.keypoints[i].depth;
    if (d <= 0 || !isCloseDepth(d, cam_, p_.stereo)) continue;
    if (f.points[i] != kNoId && !f.outlier[i]) {
      ++tracked_close;
    } else {
      ++untracked_close;
    }
  }
  const bool need_close =
      tracked_close < p_.keyframe_close_tracked_max && untracked_close > p_.keyframe_close_untracked_min;
  const float ref_ratio = kfs < 2 ? 0.4f : p_.keyframe_ref_ratio;
  const int inliers = f.matchedInliers();
  const bool c1a = f.index >= last_keyframe_.frame + static_cast<uint64_t>(p_.keyframe_max_frames);
  const bool c1b = mapping_queue == 0;
  const bool c1c = inliers < ref_matches * 0.25 || need_close;
  const bool c2 = (inliers < ref_matches * ref_ratio || need_close || turned(f)) && inliers > 15;
  return (c1a || c1b || c1c) && c2;
}

msg::KeyFramePtr Tracker::makeKeyframe(Frame& f) {
  auto kf = std::make_shared<msg::KeyFrame>();
  kf->id = keyframe_ids_.next();
  kf->frame_index = f.index;
  kf->stamp_s = f.stamp_s;
  kf->camera = cam_;
  kf->scale_factor = builder_.scales().factor;
  kf->levels = static_cast<uint8_t>(builder_.scales().levels());
  kf->keypoints = f.keypoints;
  kf->descriptors = f.descriptors;
  kf->state.id = kf->id;
  kf->state.T_w_c = f.T_w_c;
  kf->state.parent = reference_;
  kf->corrections_seen = corrections_seen_;
  kf->merges_seen = merges_seen_;
  kf->state.point_ids.assign(f.size(), kNoId);
  for (size_t i = 0; i < f.size(); ++i)
    if (f.points[i] != kNoId && !f.outlier[i]) kf->state.point_ids[i] = map_.resolve(f.points[i]);

  // New points from stereo depth, closest first: all close ones, and at least new_points_min in all
  // (ORB-SLAM2's CreateNewKeyFrame).
  std::vector<std::pair<float, int>> by_depth;
  for (size_t i = 0; i < f.size(); ++i)
    if (f.keypoints[i].depth > 0) by_depth.emplace_back(f.keypoints[i].depth, static_cast<int>(i));
  std::sort(by_depth.begin(), by_depth.end());
  const ScalePyramid& s = builder_.scales();
  const Eigen::Vector3d o_w = f.T_w_c.translation();
  int made = 0;
  for (const auto& [depth, i] : by_depth) {
    if (!p_.create_far_points && !isCloseDepth(depth, cam_, p_.stereo) && made >= p_.new_points_min) break;
    if (kf->state.point_ids[i] != kNoId) continue;
    msg::MapPoint mp;
    mp.id = point_ids_.next();
    mp.p_w = f.T_w_c * unprojectKeypoint(f.keypoints[i], cam_);
    mp.descriptor = f.descriptors[i];
    const Eigen::Vector3d ray = mp.p_w - o_w;
    const double dist = ray.norm();
    mp.normal = (ray / dist).cast<float>();
    mp.max_distance = static_cast<float>(dist * s.scale[f.keypoints[i].octave]);
    mp.min_distance = mp.max_distance / s.scale.back();
    mp.reference = kf->id;
    mp.observations = 1;
    kf->new_points.push_back(mp);
    kf->state.point_ids[i] = mp.id;
    f.points[i] = mp.id;
    f.outlier[i] = 0;
    ++made;
  }
  map_.add(*kf);
  if (keyframe_db_) keyframe_db_->add(kf->id, kf->descriptors);
  reference_ = kf->id;
  last_keyframe_ = {f.index, kf->id, f.T_w_c.linear()};
  return kf;
}

void Tracker::restartClock() {
  have_stamp_ = false;
  have_velocity_ = false;
  if (state_ != msg::TrackingState::kNotInitialized) state_ = msg::TrackingState::kLost;
}

void Tracker::apply(const msg::LocalMapUpdate& u) {
  // Keyframes made since mapping sent its corrected map (after a loop correction or a global BA merge) are
  // carried along, as mapping will carry them when they reach it (they name the counts they were made at).
  // The merge count follows the mapper's own: a mapper that resumed from a save counts from 0 again.
  const bool moved = u.corrections_seen > corrections_seen_ || u.merges_seen != merges_seen_;
  map_.apply(u, u.correction && moved);
  corrections_seen_ = std::max(corrections_seen_, u.corrections_seen);
  merges_seen_ = u.merges_seen;
  if (keyframe_db_)
    for (SlamKeyframeId k : u.culled_keyframes) keyframe_db_->remove(k);
}

}  // namespace binloop
