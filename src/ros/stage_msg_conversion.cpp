#include "binloop_ros/stage_msg_conversion.h"

#include <cmath>
#include <cstring>
#include <initializer_list>

namespace binloop_ros {
namespace {

namespace core = binloop::msg;

ros::Time stampOf(double seconds) {
  if (seconds == 0) return ros::Time(0);  // a sequence's first frame
  return toRosTime(seconds);
}

void requireId(uint64_t id, const char* field) {
  if (id == binloop::kNoId) throw ConversionError(std::string(field) + " is 0 (no id)");
}

void requireFinite(std::initializer_list<double> values, const std::string& what) {
  for (double v : values)
    if (!std::isfinite(v)) throw ConversionError(what + " has a NaN or infinite number");
}

// Larger images than any camera makes: a keyframe's grid and pyramid are sized by them.
constexpr uint32_t kMaxImageSide = 16384;

void checkSize(size_t got, size_t want, const std::string& what) {
  if (got != want)
    throw ConversionError(what + " has " + std::to_string(got) + " entries, expected " +
                          std::to_string(want));
}

binloop::MapPoint toRos(const core::MapPoint& p) {
  binloop::MapPoint m;
  m.id = p.id;
  m.position = toPoint(p.p_w);
  std::memcpy(m.descriptor.data(), p.descriptor.w.data(), binloop::Desc256::kBytes);
  m.normal.x = p.normal.x();
  m.normal.y = p.normal.y();
  m.normal.z = p.normal.z();
  m.min_distance = p.min_distance;
  m.max_distance = p.max_distance;
  m.reference = p.reference;
  m.observations = p.observations;
  return m;
}

core::MapPoint fromRos(const binloop::MapPoint& m) {
  requireId(m.id, "MapPoint.id");
  requireFinite({m.position.x, m.position.y, m.position.z, m.normal.x, m.normal.y, m.normal.z, m.min_distance,
                 m.max_distance},
                "MapPoint " + std::to_string(m.id));
  core::MapPoint p;
  p.id = m.id;
  p.p_w = Eigen::Vector3d(m.position.x, m.position.y, m.position.z);
  p.descriptor = binloop::descriptorFromBytes(m.descriptor.data());
  p.normal = Eigen::Vector3d(m.normal.x, m.normal.y, m.normal.z).cast<float>();
  p.min_distance = m.min_distance;
  p.max_distance = m.max_distance;
  p.reference = m.reference;
  p.observations = m.observations;
  return p;
}

binloop::KeyframeState toRos(const core::KeyframeState& s) {
  binloop::KeyframeState m;
  m.id = s.id;
  m.pose = toPoseMsg(s.T_w_c);
  m.point_ids = s.point_ids;
  m.covisible.reserve(s.covisible.size());
  for (const auto& e : s.covisible) {
    binloop::CovisibleEdge me;
    me.id = e.id;
    me.weight = e.weight;
    m.covisible.push_back(me);
  }
  m.parent = s.parent;
  return m;
}

core::KeyframeState fromRos(const binloop::KeyframeState& m) {
  requireId(m.id, "KeyframeState.id");
  core::KeyframeState s;
  s.id = m.id;
  s.T_w_c = toPose3(m.pose);
  s.point_ids = m.point_ids;
  s.covisible.reserve(m.covisible.size());
  for (const auto& e : m.covisible) s.covisible.push_back({e.id, e.weight});
  s.parent = m.parent;
  return s;
}

template <class RosList, class CoreList>
void convertAll(const CoreList& in, RosList* out) {
  out->reserve(in.size());
  for (const auto& x : in) out->push_back(toRos(x));
}

template <class CoreList, class RosList>
void convertAllBack(const RosList& in, CoreList* out) {
  out->reserve(in.size());
  for (const auto& x : in) out->push_back(fromRos(x));
}

std::vector<binloop::MapPointPair> toRosPairs(
    const std::vector<std::pair<binloop::MapPointId, binloop::MapPointId>>& in) {
  std::vector<binloop::MapPointPair> out(in.size());
  for (size_t i = 0; i < in.size(); ++i) {
    out[i].removed = in[i].first;
    out[i].kept = in[i].second;
  }
  return out;
}

std::vector<std::pair<binloop::MapPointId, binloop::MapPointId>> fromRosPairs(
    const std::vector<binloop::MapPointPair>& in) {
  std::vector<std::pair<binloop::MapPointId, binloop::MapPointId>> out;
  out.reserve(in.size());
  for (const auto& p : in) out.emplace_back(p.removed, p.kept);
  return out;
}

}  // namespace

binloop::KeyFrame toRos(const core::KeyFrame& kf, const std::string& frame_id) {
  binloop::KeyFrame m;
  m.header.stamp = stampOf(kf.stamp_s);
  m.header.frame_id = frame_id;
  m.id = kf.id;
  m.revision = kf.revision;
  m.frame_index = kf.frame_index;
  m.camera.fx = kf.camera.fx;
  m.camera.fy = kf.camera.fy;
  m.camera.cx = kf.camera.cx;
  m.camera.cy = kf.camera.cy;
  m.camera.baseline_m = kf.camera.baseline_m;
  m.camera.width = static_cast<uint32_t>(kf.camera.width);
  m.camera.height = static_cast<uint32_t>(kf.camera.height);
  m.scale_factor = kf.scale_factor;
  m.levels = kf.levels;
  m.keypoints.resize(kf.keypoints.size());
  for (size_t i = 0; i < kf.keypoints.size(); ++i) {
    const auto& k = kf.keypoints[i];
    auto& mk = m.keypoints[i];
    mk.x = k.x;
    mk.y = k.y;
    mk.angle = k.angle;
    mk.octave = k.octave;
    mk.right_x = k.right_x;
    mk.depth = k.depth;
  }
  m.descriptors.resize(kf.descriptors.size() * binloop::Desc256::kBytes);
  for (size_t i = 0; i < kf.descriptors.size(); ++i)
    std::memcpy(&m.descriptors[i * binloop::Desc256::kBytes], kf.descriptors[i].w.data(),
                binloop::Desc256::kBytes);
  m.state = toRos(kf.state);
  convertAll(kf.new_points, &m.new_points);
  m.corrections_seen = kf.corrections_seen;
  m.merges_seen = kf.merges_seen;
  m.resent = kf.resent;
  return m;
}

core::KeyFrame fromRos(const binloop::KeyFrame& m) {
  requireId(m.id, "KeyFrame.id");
  const size_t n = m.keypoints.size();
  checkSize(m.descriptors.size(), n * binloop::Desc256::kBytes,
            "KeyFrame.descriptors (bytes, 32 per keypoint)");
  checkSize(m.state.point_ids.size(), n, "KeyFrame.state.point_ids");
  requireFinite({m.camera.fx, m.camera.fy, m.camera.cx, m.camera.cy, m.camera.baseline_m, m.scale_factor},
                "KeyFrame.camera or scale_factor");
  if (m.camera.fx <= 0 || m.camera.fy <= 0 || m.camera.baseline_m <= 0)
    throw ConversionError("KeyFrame.camera has a non-positive focal length or baseline");
  if (m.camera.width == 0 || m.camera.height == 0 || m.camera.width > kMaxImageSide ||
      m.camera.height > kMaxImageSide)
    throw ConversionError("KeyFrame.camera is " + std::to_string(m.camera.width) + "x" +
                          std::to_string(m.camera.height) + " px (1 to " + std::to_string(kMaxImageSide) +
                          " a side)");
  if (m.scale_factor <= 1 || m.levels == 0)
    throw ConversionError("KeyFrame.scale_factor must be > 1 and levels > 0");
  core::KeyFrame kf;
  kf.id = m.id;
  kf.revision = m.revision;
  kf.frame_index = m.frame_index;
  kf.stamp_s = m.header.stamp.toSec();
  kf.camera.fx = m.camera.fx;
  kf.camera.fy = m.camera.fy;
  kf.camera.cx = m.camera.cx;
  kf.camera.cy = m.camera.cy;
  kf.camera.baseline_m = m.camera.baseline_m;
  kf.camera.width = static_cast<int>(m.camera.width);
  kf.camera.height = static_cast<int>(m.camera.height);
  kf.scale_factor = m.scale_factor;
  kf.levels = m.levels;
  kf.keypoints.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const auto& mk = m.keypoints[i];
    if (mk.octave >= m.levels)
      throw ConversionError("KeyFrame.keypoints[" + std::to_string(i) + "].octave beyond levels");
    requireFinite({mk.x, mk.y, mk.angle, mk.right_x, mk.depth},
                  "KeyFrame.keypoints[" + std::to_string(i) + "]");
    kf.keypoints[i] = {mk.x, mk.y, mk.angle, mk.octave, mk.right_x, mk.depth};
  }
  kf.descriptors.resize(n);
  for (size_t i = 0; i < n; ++i)
    kf.descriptors[i] = binloop::descriptorFromBytes(&m.descriptors[i * binloop::Desc256::kBytes]);
  kf.state = fromRos(m.state);
  convertAllBack(m.new_points, &kf.new_points);
  kf.corrections_seen = m.corrections_seen;
  kf.merges_seen = m.merges_seen;
  kf.resent = m.resent;
  // What every stage needs of a keyframe (ids, counts), checked as the stages check it.
  if (const std::string bad = binloop::msg::keyframeShapeProblem(kf); !bad.empty())
    throw ConversionError("KeyFrame: " + bad);
  return kf;
}

binloop::LocalMapUpdate toRos(const core::LocalMapUpdate& u, const std_msgs::Header& header) {
  binloop::LocalMapUpdate m;
  m.header = header;
  m.sequence = u.sequence;
  m.keyframe = u.keyframe;
  convertAll(u.keyframes, &m.keyframes);
  convertAll(u.points, &m.points);
  m.fused = toRosPairs(u.fused);
  m.culled_points = u.culled_points;
  m.culled_keyframes = u.culled_keyframes;
  m.corrections_seen = u.corrections_seen;
  m.merges_seen = u.merges_seen;
  m.correction = u.correction;
  m.whole_map = u.whole_map;
  m.tracking_keyframe_ids = u.tracking_keyframe_ids;
  m.tracking_point_ids = u.tracking_point_ids;
  m.total_ms = u.total_ms;
  m.ba_ms = u.ba_ms;
  m.triangulation_ms = u.triangulation_ms;
  m.ba_iterations = u.ba_iterations;
  m.ba_outliers = u.ba_outliers;
  m.points_triangulated = u.points_triangulated;
  m.points_fused_across_loop = u.points_fused_across_loop;
  return m;
}

core::LocalMapUpdate fromRos(const binloop::LocalMapUpdate& m) {
  core::LocalMapUpdate u;
  u.sequence = m.sequence;
  u.keyframe = m.keyframe;
  convertAllBack(m.keyframes, &u.keyframes);
  convertAllBack(m.points, &u.points);
  u.fused = fromRosPairs(m.fused);
  u.culled_points = m.culled_points;
  u.culled_keyframes = m.culled_keyframes;
  u.corrections_seen = m.corrections_seen;
  u.merges_seen = m.merges_seen;
  u.correction = m.correction;
  u.whole_map = m.whole_map;
  u.tracking_keyframe_ids = m.tracking_keyframe_ids;
  u.tracking_point_ids = m.tracking_point_ids;
  u.total_ms = m.total_ms;
  u.ba_ms = m.ba_ms;
  u.triangulation_ms = m.triangulation_ms;
  u.ba_iterations = m.ba_iterations;
  u.ba_outliers = m.ba_outliers;
  u.points_triangulated = m.points_triangulated;
  u.points_fused_across_loop = m.points_fused_across_loop;
  return u;
}

binloop::LoopCandidates toRos(const core::LoopCandidates& c, const std_msgs::Header& header) {
  binloop::LoopCandidates m;
  m.header = header;
  m.query = c.query;
  m.query_frame = c.query_frame;
  m.model = c.model;
  m.shadow = c.shadow;
  m.status = c.status;
  m.detail = c.detail;
  for (const auto& k : c.candidates) {
    binloop::LoopCandidate mk;
    mk.id = k.id;
    mk.score = k.score;
    mk.confidence = k.confidence;
    m.candidates.push_back(mk);
  }
  m.consistency = c.consistency;
  m.accepted = c.accepted;
  m.query_words = c.query_words;
  m.accepted_words = c.accepted_words;
  for (const auto& t : c.timings) {
    binloop::LoopStepTime mt;
    mt.step = t.step;
    mt.ms = t.ms;
    m.timings.push_back(mt);
  }
  m.total_ms = c.total_ms;
  return m;
}

core::LoopCandidates fromRos(const binloop::LoopCandidates& m) {
  requireId(m.query, "LoopCandidates.query");
  core::LoopCandidates c;
  c.query = m.query;
  c.query_frame = m.query_frame;
  c.model = m.model;
  c.shadow = m.shadow;
  c.status = m.status;
  c.detail = m.detail;
  for (const auto& k : m.candidates) c.candidates.push_back({k.id, k.score, k.confidence});
  c.consistency = m.consistency;
  c.accepted = m.accepted;
  c.query_words = m.query_words;
  c.accepted_words = m.accepted_words;
  for (const auto& t : m.timings) c.timings.push_back({t.step, t.ms});
  c.total_ms = m.total_ms;
  return c;
}

binloop::LoopClosure toRos(const core::LoopClosure& c, const std_msgs::Header& header) {
  binloop::LoopClosure m;
  m.header = header;
  m.query = c.query;
  m.match = c.match;
  m.query_frame = c.query_frame;
  m.match_frame = c.match_frame;
  m.model = c.model;
  m.status = core::loopStatusName(c.status);
  m.detail = c.detail;
  m.query_to_match = toPoseMsg(c.T_query_match);
  m.matches = c.matches;
  m.inliers = c.inliers;
  m.correction_m = c.correction_m;
  m.drift_bound_m = c.drift_bound_m;
  m.residual_ratio = c.residual_ratio;
  m.keyframes_corrected = c.keyframes_corrected;
  m.verify_ms = c.verify_ms;
  m.optimize_ms = c.optimize_ms;
  return m;
}

core::LoopClosure fromRos(const binloop::LoopClosure& m) {
  core::LoopClosure c;
  c.query = m.query;
  c.match = m.match;
  c.query_frame = m.query_frame;
  c.match_frame = m.match_frame;
  c.model = m.model;
  try {
    c.status = core::parseLoopStatus(m.status);
  } catch (const std::invalid_argument& e) {
    throw ConversionError(std::string("LoopClosure.status: ") + e.what());
  }
  c.detail = m.detail;
  c.T_query_match = toPose3(m.query_to_match);
  c.matches = m.matches;
  c.inliers = m.inliers;
  c.correction_m = m.correction_m;
  c.drift_bound_m = m.drift_bound_m;
  c.residual_ratio = m.residual_ratio;
  c.keyframes_corrected = m.keyframes_corrected;
  c.verify_ms = m.verify_ms;
  c.optimize_ms = m.optimize_ms;
  return c;
}

binloop::Correction toRos(const core::Correction& c, const std_msgs::Header& header) {
  binloop::Correction m;
  m.header = header;
  m.sequence = c.sequence;
  m.query = c.query;
  m.match = c.match;
  m.keyframes.resize(c.keyframes.size());
  for (size_t i = 0; i < c.keyframes.size(); ++i) {
    m.keyframes[i].id = c.keyframes[i].id;
    m.keyframes[i].before = toPoseMsg(c.keyframes[i].T_w_c_before);
    m.keyframes[i].after = toPoseMsg(c.keyframes[i].T_w_c_after);
  }
  m.fused = toRosPairs(c.fused);
  m.fuse_by_projection = c.fuse_by_projection;
  return m;
}

core::Correction fromRos(const binloop::Correction& m) {
  if (m.sequence == 0) throw ConversionError("Correction.sequence is 0 (corrections count from 1)");
  core::Correction c;
  c.sequence = m.sequence;
  c.query = m.query;
  c.match = m.match;
  c.keyframes.reserve(m.keyframes.size());
  for (const auto& k : m.keyframes) {
    requireId(k.id, "Correction.keyframes[].id");
    c.keyframes.push_back({k.id, toPose3(k.before), toPose3(k.after)});
  }
  c.fused = fromRosPairs(m.fused);
  c.fuse_by_projection = m.fuse_by_projection;
  return c;
}

binloop::TrackedFrame toRos(const core::TrackedFrame& f, const std::string& frame_id) {
  binloop::TrackedFrame m;
  m.header.stamp = stampOf(f.stamp_s);
  m.header.frame_id = frame_id;
  m.frame_index = f.frame_index;
  m.state = static_cast<uint8_t>(f.state);
  m.pose = toPoseMsg(f.T_w_c);
  m.reference = f.reference;
  m.reference_to_camera = toPoseMsg(f.T_ref_c);
  m.pose_covariance = toCovarianceMsg(f.pose_covariance);
  m.new_keyframe = f.new_keyframe;
  m.features = f.features;
  m.stereo_matches = f.stereo_matches;
  m.tracked_points = f.tracked_points;
  m.reference_points = f.reference_points;
  m.mapping_queue = f.mapping_queue;
  m.problem = f.problem;
  m.extract_ms = f.extract_ms;
  m.stereo_ms = f.stereo_ms;
  m.track_ms = f.track_ms;
  return m;
}

core::TrackedFrame fromRos(const binloop::TrackedFrame& m) {
  if (m.state > binloop::TrackedFrame::RELOCALIZED)
    throw ConversionError("TrackedFrame.state " + std::to_string(m.state) + " is not one of the constants");
  core::TrackedFrame f;
  f.frame_index = m.frame_index;
  f.stamp_s = m.header.stamp.toSec();
  f.state = static_cast<core::TrackingState>(m.state);
  f.T_w_c = toPose3(m.pose);
  f.reference = m.reference;
  f.T_ref_c = toPose3(m.reference_to_camera);
  f.pose_covariance = fromCovarianceMsg(m.pose_covariance);
  if (!f.pose_covariance.allFinite())
    throw ConversionError("TrackedFrame.pose_covariance has a NaN or infinite number");
  f.new_keyframe = m.new_keyframe;
  f.features = m.features;
  f.stereo_matches = m.stereo_matches;
  f.tracked_points = m.tracked_points;
  f.reference_points = m.reference_points;
  f.mapping_queue = m.mapping_queue;
  f.problem = m.problem;
  f.extract_ms = m.extract_ms;
  f.stereo_ms = m.stereo_ms;
  f.track_ms = m.track_ms;
  return f;
}

}  // namespace binloop_ros
