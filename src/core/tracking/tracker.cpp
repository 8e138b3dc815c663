#include "binloop/tracking/tracker.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <unordered_map>
#include <unordered_set>

#include "binloop/io/data_error.h"

namespace binloop {

namespace {

double msSinceT(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

Eigen::Vector3d unproject(const msg::KeyPoint& k, const StereoCamera& cam) {
  const double z = k.depth;
  return {(k.x - cam.cx) * z / cam.fx, (k.y - cam.cy) * z / cam.fy, z};
}

}  // namespace

const char* msg::toString(TrackingState s) {
  switch (s) {
    case TrackingState::kNotInitialized: return "not initialized";
    case TrackingState::kOk: return "ok";
    case TrackingState::kLost: return "lost";
    case TrackingState::kRelocalized: return "relocalized";
  }
  return "?";
}

Tracker::Tracker(const StereoCamera& cam, const TrackerParams& p)
    : cam_(cam), p_(p), builder_(cam, p.orb, p.stereo) {}

Pose3 Tracker::lastPose() const {
  if (const msg::KeyframeState* ref = map_.keyframe(last_ref_)) return orthonormalized(ref->T_w_c * T_ref_last_);
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
                 " s does not come after the last frame's " + std::to_string(last_stamp_) + " s; frame skipped";
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
    if (!initialize(f, &out.keyframe)) {
      tf.problem = "not initialised: " + std::to_string(f.stereo_matches) + " stereo matches, " +
                   std::to_string(p_.init_min_stereo) + " needed";
      tf.track_ms = msSinceT(t0);
      return out;
    }
    tf.state = state_;
  } else {
    const Pose3 last_pose = lastPose();
    f.T_w_c = have_velocity_ ? orthonormalized(last_pose * velocity_) : last_pose;
    bool ok = false;
    if (state_ == msg::TrackingState::kOk) {
      // The motion model when there is one; without it (right after the first keyframe), when it fails, or
      // when it holds on to only a few points (in a sharp turn a wrong prediction can still collect a dozen
      // chance matches), descriptor matching against the last frame, which needs no prediction; the
      // attempt that tracks more of the local map wins.
      Frame by_model = f;
      bool model_ok = have_velocity_ && trackLastFrame(by_model);
      const bool model_strong = model_ok && inliers_ >= p_.motion_model_min_inliers;
      model_ok = model_ok && trackLocalMap(by_model, p_.local_map_radius, p_.min_inliers);
      const int model_inliers = model_ok ? inliers_ : 0;
      if (model_ok && model_strong) {
        f = std::move(by_model);
        ok = true;
      } else {
        f.T_w_c = last_pose;
        ok = trackWithoutPrediction(f) && trackLocalMap(f, p_.local_map_radius, p_.min_inliers);
        if (model_ok && (!ok || model_inliers >= inliers_)) {
          f = std::move(by_model);
          inliers_ = model_inliers;
          ok = true;
          updateLocalKeyframes(f);  // the reference keyframe of the attempt that won
        }
      }
    }
    if (!ok) {
      // Recovery without place recognition: the local map of the last keyframes, searched wide around the
      // predicted pose. Relocalisation with hbow + PnP replaces this for long gaps (SLAM issue, not yet done).
      std::fill(f.points.begin(), f.points.end(), kNoId);
      std::fill(f.outlier.begin(), f.outlier.end(), 0);
      local_keyframes_.clear();
      if (const msg::KeyframeState* ref = map_.keyframe(reference_)) {
        local_keyframes_.push_back(ref->id);
        for (const auto& e : ref->covisible) {
          if (static_cast<int>(local_keyframes_.size()) >= p_.covisible_per_keyframe) break;
          local_keyframes_.push_back(e.id);
        }
      }
      ok = trackLocalMap(f, p_.lost_radius, p_.min_inliers_after_loss);
      if (ok && state_ == msg::TrackingState::kOk) {
        ok = true;
      } else if (ok) {
        state_ = msg::TrackingState::kRelocalized;
        frames_since_loss_ = 0;
      }
    }
    if (!ok) {
      state_ = msg::TrackingState::kLost;
      have_velocity_ = false;
      tf.state = state_;
      tf.problem = "lost: " + std::to_string(inliers_) + " inliers";
      tf.T_w_c = f.T_w_c;  // the prediction
      tf.track_ms = msSinceT(t0);
      return out;
    }
    tf.state = state_ == msg::TrackingState::kRelocalized ? state_ : msg::TrackingState::kOk;
    state_ = msg::TrackingState::kOk;
    ++frames_since_loss_;
    velocity_ = last_pose.inverse() * f.T_w_c;
    have_velocity_ = true;
    if (needKeyframe(f, mapping_queue)) out.keyframe = makeKeyframe(f);
  }

  tf.T_w_c = f.T_w_c;
  tf.tracked_points = f.matchedInliers();
  tf.reference = reference_;
  if (const msg::KeyframeState* ref = map_.keyframe(reference_)) tf.T_ref_c = ref->T_w_c.inverse() * f.T_w_c;
  if (out.keyframe) tf.new_keyframe = out.keyframe->id;
  last_ref_ = reference_;
  T_ref_last_ = tf.T_ref_c;
  last_ = std::make_unique<Frame>(std::move(f));
  tf.track_ms = msSinceT(t0);
  return out;
}

bool Tracker::initialize(Frame& f, msg::KeyFramePtr* kf) {
  if (f.stereo_matches < p_.init_min_stereo) return false;
  f.T_w_c = Pose3::Identity();
  *kf = makeKeyframe(f);
  state_ = msg::TrackingState::kOk;
  return true;
}

int Tracker::optimizePose(Frame& f) {
  std::vector<PoseObservation> obs;
  std::vector<int> index;
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
    o.u_right = k.right_x;
    o.inv_sigma2 = s.inv_sigma2[k.octave];
    obs.push_back(o);
    index.push_back(static_cast<int>(i));
  }
  if (obs.size() < 3) return 0;
  const PoseOptimizationResult r = binloop::optimizePose(cam_, orthonormalized(f.T_w_c.inverse()), obs, p_.pose);
  f.T_w_c = orthonormalized(r.T_c_w.inverse());
  int inliers = 0;
  for (size_t j = 0; j < index.size(); ++j) {
    f.outlier[index[j]] = r.outlier[j] ? 1 : 0;
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
  if (n < p_.min_last_frame_matches) {
    inliers_ = n;
    return false;
  }
  const int inl = optimizePose(f);
  for (size_t i = 0; i < f.size(); ++i)
    if (f.outlier[i]) {
      f.points[i] = kNoId;
      f.outlier[i] = 0;
    }
  inliers_ = inl;
  return inl >= 10;
}

bool Tracker::trackWithoutPrediction(Frame& f) {
  auto lookup = [this](MapPointId id) { return map_.point(id); };
  Frame& last = *last_;
  const int n = matchByDescriptor(f, last, lookup);
  if (n < p_.min_last_frame_matches) {
    inliers_ = n;
    return false;
  }
  const int inl = optimizePose(f);
  for (size_t i = 0; i < f.size(); ++i)
    if (f.outlier[i]) {
      f.points[i] = kNoId;
      f.outlier[i] = 0;
    }
  inliers_ = inl;
  return inl >= 10;
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
  const Pose3 T_c_w = f.T_w_c.inverse();
  std::vector<ProjectedPoint> visible;
  std::unordered_set<MapPointId> seen;
  for (SlamKeyframeId k : local_keyframes_) {
    const msg::KeyframeState* kf = map_.keyframe(k);
    if (!kf) continue;
    for (MapPointId id : kf->point_ids) {
      if (id == kNoId || have.count(id) || !seen.insert(id).second) continue;
      const msg::MapPoint* mp = map_.point(id);
      ProjectedPoint pp;
      if (mp && projectIntoFrame(*mp, T_c_w, cam_, builder_.scales(), &pp)) visible.push_back(pp);
    }
  }
  matchProjectedPoints(f, visible, cam_, builder_.scales(), radius, p_.projection);
  inliers_ = optimizePose(f);
  for (size_t i = 0; i < f.size(); ++i)
    if (f.outlier[i]) {
      f.points[i] = kNoId;
      f.outlier[i] = 0;
    }
  return inliers_ >= min_inliers;
}

bool Tracker::needKeyframe(const Frame& f, int mapping_queue) const {
  if (mapping_queue >= p_.max_mapping_queue) return false;
  const size_t kfs = map_.keyframeCount();
  const size_t min_obs = kfs <= 2 ? 2 : 3;
  int ref_matches = 0;
  if (const msg::KeyframeState* ref = map_.keyframe(reference_))
    for (MapPointId id : ref->point_ids)
      if (id != kNoId && map_.resolve(id) != kNoId && map_.observers(map_.resolve(id)).size() >= min_obs) ++ref_matches;
  int tracked_close = 0, untracked_close = 0;
  for (size_t i = 0; i < f.size(); ++i) {
    const float d = f.keypoints[i].depth;
    if (d <= 0 || !isCloseDepth(d, cam_, p_.stereo)) continue;
    if (f.points[i] != kNoId && !f.outlier[i]) ++tracked_close;
    else ++untracked_close;
  }
  const bool need_close = tracked_close < p_.keyframe_close_tracked_max && untracked_close > p_.keyframe_close_untracked_min;
  const float ref_ratio = kfs < 2 ? 0.4f : p_.keyframe_ref_ratio;
  const int inliers = f.matchedInliers();
  const bool c1a = f.index >= last_keyframe_frame_ + static_cast<uint64_t>(p_.keyframe_max_frames);
  const bool c1b = mapping_queue == 0;
  const bool c1c = inliers < ref_matches * 0.25 || need_close;
  const bool c2 = (inliers < ref_matches * ref_ratio || need_close) && inliers > 15;
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
    mp.p_w = f.T_w_c * unproject(f.keypoints[i], cam_);
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
  reference_ = kf->id;
  last_keyframe_frame_ = f.index;
  return kf;
}

void Tracker::apply(const msg::LocalMapUpdate& u) { map_.apply(u); }

void Tracker::apply(const msg::Correction& c) { map_.apply(c); }

}  // namespace binloop
