// LoopDetector's save/load (the loop detector's state file).
#include <map>

#include "binloop/io/state_file.h"
#include "binloop/loop/loop_detector.h"
#include "binloop/util/sorted_keys.h"

namespace binloop {

std::vector<std::string> LoopDetector::indexedModels() const {
  std::vector<std::string> names{pending_ ? pending_->name : active_name_};
  for (const Model& m : shadow_) names.push_back(m.name);
  return names;
}

void LoopDetector::save(StateWriter& w) const {
  const std::vector<std::string> models = indexedModels();
  w.put<uint64_t>(models.size());
  for (const std::string& m : models) {
    w.putString(m);
    w.putString(identity_ ? identity_(m) : "");
  }
  w.put<uint64_t>(order_.size());
  for (size_t k = 0; k < order_.size(); ++k) {
    w.put<uint64_t>(order_[k]);
    w.putArray(descriptors_[k]);
  }
  w.put<uint64_t>(covisible_.size());
  for (SlamKeyframeId id : sortedKeys(covisible_)) {
    const auto& edges = covisible_.at(id);
    w.put<uint64_t>(id);
    w.put<uint64_t>(edges.size());
    for (const auto& [k, weight] : edges) {
      w.put<uint64_t>(k);
      w.put<uint32_t>(weight);
    }
  }
}

void LoopDetector::load(StateReader& r) {
  if (!order_.empty()) r.fail("the loop detector already holds keyframes; a map loads into a new one");
  std::map<std::string, std::string> saved;
  const uint64_t models = r.getCount("models", 16);
  for (uint64_t i = 0; i < models; ++i) {
    std::string name = r.getString("model name");
    saved[name] = r.getString("model vocabulary");
  }
  for (const std::string& m : indexedModels()) {
    auto it = saved.find(m);
    const std::string now = identity_ ? identity_(m) : "";
    if (it != saved.end() && !it->second.empty() && !now.empty() && it->second != now) {
      r.fail(
          "the map's " + m + " index was built with " + it->second + ", but this loop detector's " + m +
          " is " + now +
          ": the same keyframes would give another index (load it with that vocabulary, or another model)");
    }
  }
  const uint64_t n = r.getCount("keyframes", 16);
  for (uint64_t k = 0; k < n; ++k) {
    const SlamKeyframeId id = r.get<uint64_t>("keyframe id");
    if (dense_.count(id)) r.fail("keyframe " + std::to_string(id) + " twice");
    dense_[id] = static_cast<KeyframeId>(order_.size());
    order_.push_back(id);
    descriptors_.push_back(r.getArray<Desc256>("keyframe descriptors"));
    if (descriptors_.back().empty()) r.fail("keyframe " + std::to_string(id) + " without descriptors");
  }
  const uint64_t c = r.getCount("covisibility", 16);
  for (uint64_t i = 0; i < c; ++i) {
    auto& edges = covisible_[r.get<uint64_t>("covisible keyframe")];
    const uint64_t e = r.getCount("covisible edges", 12);
    for (uint64_t j = 0; j < e; ++j) {
      const SlamKeyframeId k = r.get<uint64_t>("covisible keyframe");
      edges[k] = r.get<uint32_t>("covisibility weight");
    }
  }
  r.expectEnd();
  if (pending_) {
    active_ = std::move(*pending_);
    active_name_ = active_.name;
    pending_.reset();
  }
  fillFrom(active_);
  for (Model& m : shadow_) fillFrom(m);
}

}  // namespace binloop
