#include "binloop/place/place_recognizer.h"

#include <algorithm>

#include "binloop/place/place_error.h"

namespace binloop {

std::string statusName(QueryStatus s) {
  switch (s) {
    case QueryStatus::kFound:
      return "found";
    case QueryStatus::kUnknownKeyframe:
      return "unknown_keyframe";
    case QueryStatus::kEmptyDatabase:
      return "empty_database";
    case QueryStatus::kNoReference:
      return "no_reference";
    case QueryStatus::kNoPreCandidates:
      return "no_pre_candidates";
    case QueryStatus::kBelowReference:
      return "below_reference";
  }
  return "?";
}

double PlaceRecognizer::add(KeyframeId id, const Descriptors& d) {
  if (d.empty()) throw PlaceError(name() + ": keyframe " + std::to_string(id) + " has no descriptors");
  if (known(id)) throw PlaceError(name() + ": keyframe " + std::to_string(id) + " was added before");
  const auto t0 = std::chrono::steady_clock::now();
  addSignature(static_cast<Slot>(order_.size()), d);
  const double ms = msSince(t0);
  position_[id] = static_cast<Slot>(order_.size());
  order_.push_back(id);
  if (keep_descriptors_) descriptors_[id] = d;
  return ms;
}

QueryResult PlaceRecognizer::query(KeyframeId id, const QueryScope& scope) const {
  const auto t0 = std::chrono::steady_clock::now();
  QueryResult r;
  if (!known(id)) {
    r.status = QueryStatus::kUnknownKeyframe;
    r.detail = "keyframe " + std::to_string(id) + " was never added";
    return r;
  }
  SlotScope s;
  s.query = position_.at(id);
  s.excluded.assign(order_.size(), 0);
  s.excluded[s.query] = 1;
  s.reference_named = scope.reference.size();
  s.max_ranked = scope.max_ranked;
  for (KeyframeId k : scope.reference) {
    Slot slot;
    if (!findSlot(k, &slot) || s.excluded[slot]) continue;  // unknown, the query itself, or named twice
    s.excluded[slot] = 1;
    s.reference.push_back(slot);
  }
  for (KeyframeId k : scope.ignore) {
    Slot slot;
    if (findSlot(k, &slot)) s.excluded[slot] = 1;
  }
  size_t outside = 0;
  for (char e : s.excluded) outside += !e;
  if (outside == 0) {
    r.status = QueryStatus::kEmptyDatabase;
    r.detail = "no keyframe outside the query's scope";
  } else {
    r = querySignature(s);
  }
  r.total_ms = msSince(t0);
  return r;
}

const Descriptors& PlaceRecognizer::descriptors(KeyframeId id) const {
  const auto it = descriptors_.find(id);
  if (it == descriptors_.end())
    throw PlaceError(name() + ": no descriptors kept for keyframe " + std::to_string(id));
  return it->second;
}

void PlaceRecognizer::rebuildInto(PlaceRecognizer& other) const {
  for (KeyframeId id : order_) other.add(id, descriptors(id));
}

void PlaceRecognizer::offer(QueryResult& r, const Candidate& c, bool passes) {
  if (passes) {
    r.candidates.push_back(c);
  } else if (!r.has_best_rejected || c.confidence > r.best_rejected.confidence) {
    r.has_best_rejected = true;
    r.best_rejected = c;
  }
}

void PlaceRecognizer::sortCandidates(QueryResult& r) {
  std::sort(r.candidates.begin(), r.candidates.end(), [](const Candidate& a, const Candidate& b) {
    return a.score != b.score ? a.score > b.score : a.id < b.id;
  });
}

void PlaceRecognizer::keepRanked(QueryResult& r, std::vector<Candidate> all, size_t n) {
  const auto better = [](const Candidate& a, const Candidate& b) {
    return a.score != b.score ? a.score > b.score : a.id < b.id;
  };
  n = std::min(n, all.size());
  std::partial_sort(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(n), all.end(), better);
  all.resize(n);
  r.ranked = std::move(all);
}

PlaceRecognizer::Slot PlaceRecognizer::slotOf(KeyframeId id) const {
  Slot s;
  if (!findSlot(id, &s)) throw PlaceError(name() + ": keyframe " + std::to_string(id) + " was never added");
  return s;
}

bool PlaceRecognizer::findSlot(KeyframeId id, Slot* s) const {
  const auto it = position_.find(id);
  if (it == position_.end()) return false;
  *s = it->second;
  return true;
}

std::vector<KeyframeId> PlaceRecognizer::group(KeyframeId id) const {
  if (group_fn_) return group_fn_(id);
  std::vector<KeyframeId> g;
  const auto it = position_.find(id);
  if (it == position_.end()) return g;
  const size_t p = it->second;
  for (size_t q = p >= 2 ? p - 2 : 0; q <= p + 2 && q < order_.size(); ++q)
    if (q != p) g.push_back(order_[q]);
  return g;
}

}  // namespace binloop
