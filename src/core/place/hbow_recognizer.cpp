#include "binloop/place/hbow_recognizer.h"

#include <algorithm>
#include <limits>
#include <sstream>

#include "binloop/place/place_error.h"

namespace binloop {

HbowRecognizer::HbowRecognizer(std::shared_ptr<const VocabularyTree> voc) : voc_(std::move(voc)) {
  if (!voc_) throw PlaceError("hbow: no vocabulary");
  inverted_.resize(voc_->words());
}

std::shared_ptr<const VocabularyTree> HbowRecognizer::loadVocabulary(const std::string& path) {
  ModelReader r(path);
  r.expectType(ModelType::kHbow);
  auto t = std::make_shared<VocabularyTree>(VocabularyTree::read(r));
  r.expectEnd();
  return t;
}

void HbowRecognizer::addSignature(KeyframeId id, const Descriptors& d) {
  BowVector& b = bows_[id];
  voc_->transform(d, &b);
  for (const auto& e : b) inverted_[e.word].push_back(id);
}

size_t HbowRecognizer::indexBytesPerKeyframe() const {
  if (bows_.empty()) return 0;
  size_t entries = 0;
  for (const auto& [id, b] : bows_) entries += b.size();
  // BoW entry (word + weight) and one inverted-index entry per word of each keyframe.
  return entries * (sizeof(BowEntry) + sizeof(KeyframeId)) / bows_.size();
}

QueryResult HbowRecognizer::querySignature(KeyframeId id, const QueryScope& scope,
                                           const std::function<bool(KeyframeId)>& excluded) const {
  QueryResult r;
  const BowVector& q = bows_.at(id);
  auto t = std::chrono::steady_clock::now();
  double min_score = std::numeric_limits<double>::max();
  int refs = 0;
  for (KeyframeId k : scope.reference)
    if (known(k)) min_score = std::min(min_score, l1Score(q, bows_.at(k))), ++refs;
  r.timings.push_back({"reference", msSince(t)});
  if (refs == 0) {
    r.status = QueryStatus::kNoReference;
    r.detail = "none of the " + std::to_string(scope.reference.size()) + " reference keyframes is in the database";
    return r;
  }
  r.threshold = min_score;

  t = std::chrono::steady_clock::now();
  std::unordered_map<KeyframeId, int> common;
  for (const auto& e : q)
    for (KeyframeId k : inverted_[e.word])
      if (!excluded(k)) common[k]++;
  int max_common = 0;
  for (const auto& [k, n] : common) max_common = std::max(max_common, n);
  const int min_common = static_cast<int>(0.8f * max_common);
  r.timings.push_back({"common_words", msSince(t)});
  if (common.empty()) {
    r.status = QueryStatus::kNoPreCandidates;
    r.detail = "no keyframe outside the scope shares a word with the query";
    return r;
  }

  t = std::chrono::steady_clock::now();
  std::unordered_map<KeyframeId, double> scored;
  for (const auto& [k, n] : common) {
    if (n <= min_common) continue;
    const double s = l1Score(q, bows_.at(k));
    if (s >= min_score) {
      scored[k] = s;
    } else {
      offer(r, {k, s, s / std::max(min_score, 1e-9)}, false);
    }
  }
  r.timings.push_back({"score", msSince(t)});
  std::ostringstream detail;
  detail << "bar " << min_score << " from " << refs << " reference keyframes; " << common.size()
         << " share words (max " << max_common << "); " << scored.size() << " reach the bar";
  r.detail = detail.str();
  if (scored.empty()) {
    r.status = QueryStatus::kBelowReference;
    return r;
  }

  t = std::chrono::steady_clock::now();
  struct Group {
    double acc, best;
    KeyframeId best_id;
  };
  std::vector<Group> groups;
  double best_acc = 0;
  for (const auto& [k, s] : scored) {
    Group g{s, s, k};
    for (KeyframeId n : group(k)) {
      const auto it = scored.find(n);
      if (it == scored.end()) continue;
      g.acc += it->second;
      if (it->second > g.best) g.best = it->second, g.best_id = n;
    }
    best_acc = std::max(best_acc, g.acc);
    groups.push_back(g);
  }
  std::sort(groups.begin(), groups.end(), [](const Group& a, const Group& b) { return a.acc > b.acc; });
  const double retain = 0.75 * best_acc;
  std::vector<KeyframeId> seen;
  for (const Group& g : groups) {
    if (g.acc < retain) break;
    if (std::find(seen.begin(), seen.end(), g.best_id) != seen.end()) continue;
    seen.push_back(g.best_id);
    r.candidates.push_back({g.best_id, g.acc, g.best / std::max(min_score, 1e-9)});
  }
  r.timings.push_back({"group", msSince(t)});
  r.status = QueryStatus::kFound;
  return r;
}

}  // namespace binloop
