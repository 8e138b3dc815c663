#include "binloop/messages/message_state.h"

#include <Eigen/Geometry>

namespace binloop {

// The 3x4 matrix itself, not a quaternion: a load and a save then give the same bytes.
void writePose(StateWriter& w, const Pose3& T) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) w.put(T.matrix()(r, c));
}

Pose3 readPose(StateReader& r, const char* what) {
  Pose3 T = Pose3::Identity();
  for (int i = 0; i < 3; ++i)
    for (int c = 0; c < 4; ++c) T.matrix()(i, c) = r.get<double>(what);
  const double off = (T.linear().transpose() * T.linear() - Eigen::Matrix3d::Identity()).norm();
  if (!(off < 1e-6) || !T.matrix().allFinite()) r.fail(std::string("not a rigid transform in ") + what);
  return T;
}

void writeCamera(StateWriter& w, const StereoCamera& c) {
  for (double v : {c.fx, c.fy, c.cx, c.cy, c.baseline_m}) w.put(v);
  w.put<int32_t>(c.width);
  w.put<int32_t>(c.height);
}

StereoCamera readCamera(StateReader& r) {
  StereoCamera c;
  for (double* v : {&c.fx, &c.fy, &c.cx, &c.cy, &c.baseline_m}) *v = r.get<double>("camera");
  c.width = r.get<int32_t>("camera");
  c.height = r.get<int32_t>("camera");
  return c;
}

void writeMapPoint(StateWriter& w, const msg::MapPoint& p) {
  w.put<uint64_t>(p.id);
  for (int i = 0; i < 3; ++i) w.put(p.p_w[i]);
  for (uint64_t x : p.descriptor.w) w.put(x);
  for (int i = 0; i < 3; ++i) w.put(p.normal[i]);
  w.put(p.min_distance);
  w.put(p.max_distance);
  w.put<uint64_t>(p.reference);
  w.put<uint32_t>(p.observations);
}

msg::MapPoint readMapPoint(StateReader& r) {
  msg::MapPoint p;
  p.id = r.get<uint64_t>("map point id");
  for (int i = 0; i < 3; ++i) p.p_w[i] = r.get<double>("map point position");
  for (uint64_t& x : p.descriptor.w) x = r.get<uint64_t>("map point descriptor");
  for (int i = 0; i < 3; ++i) p.normal[i] = r.get<float>("map point normal");
  p.min_distance = r.get<float>("map point range");
  p.max_distance = r.get<float>("map point range");
  p.reference = r.get<uint64_t>("map point reference");
  p.observations = r.get<uint32_t>("map point observations");
  return p;
}

void writeKeyframeState(StateWriter& w, const msg::KeyframeState& s) {
  w.put<uint64_t>(s.id);
  writePose(w, s.T_w_c);
  w.putArray(s.point_ids);
  w.put<uint64_t>(s.covisible.size());
  for (const auto& e : s.covisible) {
    w.put<uint64_t>(e.id);
    w.put<uint32_t>(e.weight);
  }
  w.put<uint64_t>(s.parent);
}

msg::KeyframeState readKeyframeState(StateReader& r) {
  msg::KeyframeState s;
  s.id = r.get<uint64_t>("keyframe id");
  s.T_w_c = readPose(r, "keyframe pose");
  s.point_ids = r.getArray<MapPointId>("keyframe point ids");
  s.covisible.resize(r.getCount("covisible keyframes", 12));
  for (auto& e : s.covisible) {
    e.id = r.get<uint64_t>("covisible keyframe");
    e.weight = r.get<uint32_t>("covisibility weight");
  }
  s.parent = r.get<uint64_t>("keyframe parent");
  return s;
}

void writeKeyPoints(StateWriter& w, const std::vector<msg::KeyPoint>& ks) {
  w.put<uint64_t>(ks.size());
  for (const auto& k : ks) {
    for (float v : {k.x, k.y, k.angle, k.right_x, k.depth}) w.put(v);
    w.put(k.octave);
  }
}

std::vector<msg::KeyPoint> readKeyPoints(StateReader& r) {
  std::vector<msg::KeyPoint> ks(r.getCount("keypoints", 21));
  for (auto& k : ks) {
    for (float* v : {&k.x, &k.y, &k.angle, &k.right_x, &k.depth}) *v = r.get<float>("keypoint");
    k.octave = r.get<uint8_t>("keypoint octave");
  }
  return ks;
}

void writeKeyFrame(StateWriter& w, const msg::KeyFrame& kf) {
  w.put<uint64_t>(kf.id);
  w.put<uint32_t>(kf.revision);
  w.put<uint64_t>(kf.frame_index);
  w.put(kf.stamp_s);
  writeCamera(w, kf.camera);
  w.put(kf.scale_factor);
  w.put(kf.levels);
  writeKeyPoints(w, kf.keypoints);
  w.putArray(kf.descriptors);
  writeKeyframeState(w, kf.state);
  w.put<uint64_t>(kf.new_points.size());
  for (const auto& p : kf.new_points) writeMapPoint(w, p);
  w.put<uint64_t>(kf.corrections_seen);
}

msg::KeyFrame readKeyFrame(StateReader& r) {
  msg::KeyFrame kf;
  kf.id = r.get<uint64_t>("keyframe id");
  kf.revision = r.get<uint32_t>("keyframe revision");
  kf.frame_index = r.get<uint64_t>("keyframe frame index");
  kf.stamp_s = r.get<double>("keyframe stamp");
  kf.camera = readCamera(r);
  kf.scale_factor = r.get<float>("keyframe scale factor");
  kf.levels = r.get<uint8_t>("keyframe levels");
  kf.keypoints = readKeyPoints(r);
  kf.descriptors = r.getArray<Desc256>("keyframe descriptors");
  kf.state = readKeyframeState(r);
  kf.new_points.resize(r.getCount("keyframe new points", 100));
  for (auto& p : kf.new_points) p = readMapPoint(r);
  kf.corrections_seen = r.get<uint64_t>("keyframe corrections seen");
  if (const std::string bad = msg::keyframeShapeProblem(kf); !bad.empty()) r.fail(bad);
  return kf;
}

}  // namespace binloop
