// LocalMapper's save/load (local mapping's state file: the map it owns).

#include "binloop/io/state_file.h"
#include "binloop/mapping/local_mapper.h"
#include "binloop/messages/message_state.h"
#include "binloop/util/sorted_keys.h"

namespace binloop {
namespace {

template <class K>
void writeCounts(StateWriter& w, const std::map<K, int>& m) {
  w.put<uint64_t>(m.size());
  for (const auto& [k, v] : m) {
    w.put<uint64_t>(k);
    w.put<int32_t>(v);
  }
}

template <class K>
std::map<K, int> readCounts(StateReader& r, const char* what) {
  std::map<K, int> m;
  const uint64_t n = r.getCount(what, 12);
  for (uint64_t i = 0; i < n; ++i) {
    const K k = r.get<uint64_t>(what);
    m[k] = r.get<int32_t>(what);
  }
  return m;
}

}  // namespace

void LocalMapper::save(StateWriter& w) const {
  writeCamera(w, camera_);
  w.put<float>(scales_.factor);
  w.put<int32_t>(scales_.levels());
  w.put<uint64_t>(map_.keyframes().size());
  for (SlamKeyframeId id : sortedKeys(map_.keyframes())) {
    const KF& kf = map_.keyframes().at(id);
    writeKeyframeState(w, kf.state);
    w.put<uint64_t>(kf.frame_index);
    w.put<uint64_t>(kf.seq);
    w.put(kf.stamp_s);
    writeKeyPoints(w, kf.keypoints);
    w.putArray(kf.descriptors);
    writeCounts(w, kf.weights);
  }
  w.put<uint64_t>(map_.points().size());
  for (MapPointId id : sortedKeys(map_.points())) {
    const MP& mp = map_.points().at(id);
    writeMapPoint(w, mp.state);
    writeCounts(w, mp.obs);
    w.put<uint64_t>(mp.first_seq);
  }
  map_.saveFusions(w);
  map_.saveCulled(w);
  w.putArray(std::vector<MapPointId>(recent_.begin(), recent_.end()));
  w.put<uint64_t>(point_ids_.issued());
  w.put<uint64_t>(seq_);
  w.put<uint64_t>(updates_);
  w.put<uint64_t>(first_kf_);
  history_.save(w);
}

void LocalMapper::load(StateReader& r) {
  if (!map_.keyframes().empty()) r.fail("local mapping already holds a map; a map loads into a new one");
  camera_ = readCamera(r);
  const float factor = r.get<float>("scale factor");
  const int levels = r.get<int32_t>("pyramid levels");
  if (levels < 0 || levels > 64 || (levels > 0 && !(factor > 1.f && factor < 4.f)))
    r.fail("impossible scale pyramid");
  scales_ = levels > 0 ? ScalePyramid(factor, levels) : ScalePyramid();
  const uint64_t kfs = r.getCount("keyframes", 100);
  for (uint64_t i = 0; i < kfs; ++i) {
    msg::KeyframeState s = readKeyframeState(r);
    KF& kf = map_.keyframes()[s.id];
    kf.state = std::move(s);
    kf.frame_index = r.get<uint64_t>("keyframe frame index");
    kf.seq = r.get<uint64_t>("keyframe sequence");
    kf.stamp_s = r.get<double>("keyframe stamp");
    kf.keypoints = readKeyPoints(r);
    kf.descriptors = r.getArray<Desc256>("keyframe descriptors");
    kf.weights = readCounts<SlamKeyframeId>(r, "covisibility weights");
    if (kf.keypoints.size() != kf.descriptors.size() || kf.keypoints.size() != kf.state.point_ids.size()) {
      r.fail("keyframe " + std::to_string(kf.state.id) +
             ": keypoints, descriptors and point ids differ in number");
    }
    kf.grid = KeypointGrid(kf.keypoints, camera_.width, camera_.height);
  }
  const uint64_t pts = r.getCount("map points", 100);
  for (uint64_t i = 0; i < pts; ++i) {
    msg::MapPoint s = readMapPoint(r);
    MP& mp = map_.points()[s.id];
    mp.state = std::move(s);
    mp.obs = readCounts<SlamKeyframeId>(r, "point observations");
    mp.first_seq = r.get<uint64_t>("point sequence");
    for (const auto& [k, idx] : mp.obs) {
      auto it = map_.keyframes().find(k);
      if (it == map_.keyframes().end() || idx < 0 || static_cast<size_t>(idx) >= it->second.keypoints.size())
        r.fail("map point " + std::to_string(mp.state.id) + " is seen by an unknown keyframe or keypoint");
    }
  }
  map_.loadFusions(r, "fused points");
  map_.loadCulled(r);
  const std::vector<MapPointId> recent = r.getArray<MapPointId>("recent points");
  recent_.assign(recent.begin(), recent.end());
  point_ids_.restore(r.get<uint64_t>("points issued"));
  seq_ = r.get<uint64_t>("keyframe sequence");
  updates_ = r.get<uint64_t>("updates sent");
  first_kf_ = r.get<uint64_t>("first keyframe");
  history_.load(r);
  r.expectEnd();
}

}  // namespace binloop
