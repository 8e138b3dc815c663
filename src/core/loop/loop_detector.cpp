#include "binloop/loop/loop_detector.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>

namespace binloop {

LoopDetector::LoopDetector(const LoopDetectorParams& p, ModelFactory make)
    : p_(p), make_(std::move(make)), active_(makeModel(p.model)), active_name_(p.model) {}

LoopDetector::Model LoopDetector::makeModel(const std::string& name) const {
  Model m{name, make_(name), ConsistencyGroups(p_.consistency, p_.consistency_gap)};
  if (!m.recognizer) throw PlaceError("loop detector: no model made for '" + name + "'");
  // The stage's own store is the one copy of the descriptors (models are replaced on a switch).
  m.recognizer->setKeepDescriptors(false);
  // hbow sums scores over a candidate's group: its covisible keyframes, as the detector knows them.
  m.recognizer->setGroupFunction([this](KeyframeId k) {
    std::vector<KeyframeId> out;
    if (k >= order_.size()) return out;
    auto it = covisible_.find(order_[k]);
    if (it == covisible_.end()) return out;
    for (const auto& [id, w] : it->second) {
      auto d = dense_.find(id);
      if (d != dense_.end()) out.push_back(d->second);
    }
    return out;
  });
  return m;
}

void LoopDetector::fillFrom(Model& m) const {
  for (size_t k = 0; k < order_.size(); ++k) m.recognizer->add(static_cast<KeyframeId>(k), descriptors_[k]);
}

void LoopDetector::switchModel(const std::string& name) {
  pending_ = std::make_unique<Model>(makeModel(name));
}

void LoopDetector::reconfigure(const LoopDetectorParams& p, ModelFactory make) {
  LoopDetectorParams old_p = p_;
  ModelFactory old_make = make_;
  p_ = p;
  make_ = std::move(make);
  try {
    pending_ = std::make_unique<Model>(makeModel(p.model));
  } catch (...) {
    p_ = old_p;
    make_ = std::move(old_make);
    throw;
  }
}

void LoopDetector::setShadowModels(const std::vector<std::string>& names) {
  std::vector<Model> models;
  for (const std::string& n : names) {
    if (n == active_name_) continue;
    models.push_back(makeModel(n));
    fillFrom(models.back());
  }
  shadow_ = std::move(models);
}

std::vector<KeyframeId> LoopDetector::referenceOf(SlamKeyframeId id) const {
  std::vector<std::pair<uint32_t, SlamKeyframeId>> by_weight;
  auto it = covisible_.find(id);
  if (it != covisible_.end())
    for (const auto& [k, w] : it->second) by_weight.emplace_back(w, k);
  std::sort(by_weight.begin(), by_weight.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first > b.first : a.second < b.second;
  });
  std::vector<KeyframeId> out;
  for (const auto& [w, k] : by_weight) {
    if (static_cast<int>(out.size()) >= p_.max_reference) break;
    auto d = dense_.find(k);
    if (d != dense_.end()) out.push_back(d->second);
  }
  return out;
}

std::set<SlamKeyframeId> LoopDetector::groupOf(SlamKeyframeId id) const {
  std::set<SlamKeyframeId> g{id};
  auto it = covisible_.find(id);
  if (it != covisible_.end())
    for (const auto& [k, w] : it->second) g.insert(k);
  return g;
}

std::shared_ptr<msg::LoopCandidates> LoopDetector::query(Model& m, SlamKeyframeId id, uint64_t frame,
                                                         bool shadow) const {
  const KeyframeId q = dense_.at(id);
  QueryScope scope;
  scope.reference = referenceOf(id);
  for (KeyframeId k = q > static_cast<KeyframeId>(p_.ignore_recent) ? q - p_.ignore_recent : 0; k < q; ++k)
    scope.ignore.push_back(k);
  // Keyframes that already share points with the query are the same place, not a loop (ORB-SLAM2).
  for (SlamKeyframeId k : groupOf(id)) {
    auto d = dense_.find(k);
    if (d != dense_.end() && d->second != q) scope.ignore.push_back(d->second);
  }
  const QueryResult r = m.recognizer->query(q, scope);
  auto out = std::make_shared<msg::LoopCandidates>();
  out->query = id;
  out->query_frame = frame;
  out->model = m.name;
  out->shadow = shadow;
  out->status = statusName(r.status);
  out->detail = r.detail;
  std::vector<ConsistencyGroups::Proposal> proposals;
  for (const Candidate& c : r.candidates) {
    const SlamKeyframeId cid = order_.at(c.id);
    out->candidates.push_back({cid, c.score, c.confidence});
    proposals.push_back({cid, groupOf(cid)});
  }
  const ConsistencyGroups::Result cr = m.consistency.update(proposals);
  out->consistency = cr.longest;
  out->accepted = cr.accepted;
  if (!shadow && cr.accepted != kNoId) {
    out->query_words = m.recognizer->matchWords(descriptors_[q]);
    if (!out->query_words.empty())
      out->accepted_words = m.recognizer->matchWords(descriptors_[dense_.at(cr.accepted)]);
  }
  for (const StepTime& t : r.timings) out->timings.push_back({t.step, t.ms});
  out->total_ms = r.total_ms;
  return out;
}

LoopDetector::Output LoopDetector::process(const msg::KeyFrame& kf) {
  if (kf.descriptors.empty())
    throw std::invalid_argument("keyframe " + std::to_string(kf.id) + " has no descriptors");
  for (const msg::CovisibleEdge& e : kf.state.covisible) {
    covisible_[kf.id][e.id] = e.weight;
    covisible_[e.id][kf.id] = e.weight;
  }
  Output out;
  if (pending_) {
    const auto ts = std::chrono::steady_clock::now();
    fillFrom(*pending_);
    out.switch_ms = msSince(ts);
    active_ = std::move(*pending_);
    active_name_ = active_.name;
    pending_.reset();
  }
  if (dense_.count(kf.id)) return out;  // a later revision: covisibility only
  const KeyframeId dense = static_cast<KeyframeId>(order_.size());
  // add() throws only for an empty set or a known id, both ruled out above. Each model's signature time is
  // reported as its own first step (the detection goals exclude it).
  const double active_signature_ms = active_.recognizer->add(dense, kf.descriptors);
  std::vector<double> shadow_signature_ms;
  for (Model& m : shadow_) shadow_signature_ms.push_back(m.recognizer->add(dense, kf.descriptors));
  dense_[kf.id] = dense;
  order_.push_back(kf.id);
  descriptors_.push_back(kf.descriptors);
  if (kf.resent) return out;  // a keyframe of the map sent again: held and indexed, not a query
  auto withSignature = [](std::shared_ptr<msg::LoopCandidates> c, double ms) {
    c->timings.insert(c->timings.begin(), msg::LoopStepTime{"signature", ms});
    c->total_ms += ms;
    return c;
  };
  out.active = withSignature(query(active_, kf.id, kf.frame_index, false), active_signature_ms);
  for (size_t i = 0; i < shadow_.size(); ++i) {
    out.shadow.push_back(
        withSignature(query(shadow_[i], kf.id, kf.frame_index, true), shadow_signature_ms[i]));
  }
  return out;
}

}  // namespace binloop
