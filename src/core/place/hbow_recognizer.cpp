#include "binloop/place/hbow_recognizer.h"

#include <algorithm>
#include <limits>
#include <sstream>

#include "binloop/place/place_error.h"
#include "binloop/place/slot_counter.h"

namespace binloop {

HbowRecognizer::HbowRecognizer(std::shared_ptr<const VocabularyTree> voc, double min_bar)
    : voc_(std::move(voc)), min_bar_(min_bar) {
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

void HbowRecognizer::addSignature(Slot slot, const Descriptors& d) {
  BowVector b;
  voc_->transform(d, &b);
  for (const auto& e : b) inverted_[e.word].push_back(slot);
  bows_.push_back(std::move(b));
}

size_t HbowRecognizer::indexBytesPerKeyframe() const {
  if (bows_.empty()) return 0;
  size_t entries = 0;
  for (const auto& b : bows_) entries += b.size();
  // BoW entry (word + weight) and one inverted-index entry per word of each keyframe.
  return entries * (sizeof(BowEntry) + sizeof(Slot)) / bows_.size();
}

QueryResult HbowRecognizer::querySignature(const SlotScope& scope) const {
  QueryResult r;
  const BowVector& q = bows_[scope.query];
  auto t = std::chrono::steady_clock::now();
  double min_score = std::numeric_limits<double>::max();
  for (Slot k : scope.reference) min_score = std::min(min_score, l1Score(q, bows_[k]));
  const size_t refs = scope.reference.size();
  r.timings.push_back({"reference", msSince(t)});
  if (refs == 0) {
    r.status = QueryStatus::kNoReference;
    r.detail = "none of the " + std::to_string(scope.reference_named) + " reference keyframes is in the database";
    return r;
  }
  const double reference_score = min_score;
  min_score = std::max(min_score, min_bar_);
  r.threshold = min_score;

  t = std::chrono::steady_clock::now();
  // Common words per keyframe in a dense array; exclusion is tested once per keyframe, not per entry.
  SlotCounter common(bows_.size());
  for (const auto& e : q) common.add(inverted_[e.word]);
  const std::vector<Slot>& touched = common.touched();
  size_t sharing = 0;
  uint32_t max_common = 0;
  for (Slot k : touched) {
    if (scope.excluded[k]) continue;
    ++sharing;
    max_common = std::max(max_common, common[k]);
  }
  const uint32_t min_common = static_cast<uint32_t>(0.8f * max_common);
  r.timings.push_back({"common_words", msSince(t)});
  if (sharing == 0) {
    r.status = QueryStatus::kNoPreCandidates;
    r.detail = "no keyframe outside the scope shares a word with the query";
    return r;
  }

  t = std::chrono::steady_clock::now();
  std::vector<double> score(bows_.size(), -1);  // L1 scores are in [0, 1]; -1 = not scored
  std::vector<Slot> scored;
  for (Slot k : touched) {
    if (scope.excluded[k] || common[k] <= min_common) continue;
    const double s = l1Score(q, bows_[k]);
    if (s >= min_score) {
      score[k] = s;
      scored.push_back(k);
    } else {
      offer(r, {idAt(k), s, s / std::max(min_score, 1e-9)}, false);
    }
  }
  r.timings.push_back({"score", msSince(t)});
  std::ostringstream detail;
  detail << "bar " << min_score;
  if (reference_score < min_score) detail << " (floor; the references scored " << reference_score << ")";
  detail << " from " << refs << " reference keyframes; " << sharing
         << " share words (max " << max_common << "); " << scored.size() << " reach the bar";
  r.detail = detail.str();
  if (scored.empty()) {
    r.status = QueryStatus::kBelowReference;
    return r;
  }

  t = std::chrono::steady_clock::now();
  struct Group {
    double acc, best;
    Slot best_slot;
  };
  std::vector<Group> groups;
  double best_acc = 0;
  for (Slot k : scored) {
    Group g{score[k], score[k], k};
    for (KeyframeId n : group(idAt(k))) {
      Slot ns;
      if (!findSlot(n, &ns) || score[ns] < 0) continue;
      g.acc += score[ns];
      if (score[ns] > g.best) g.best = score[ns], g.best_slot = ns;
    }
    best_acc = std::max(best_acc, g.acc);
    groups.push_back(g);
  }
  std::stable_sort(groups.begin(), groups.end(), [](const Group& a, const Group& b) { return a.acc > b.acc; });
  const double retain = 0.75 * best_acc;
  std::vector<Slot> seen;
  for (const Group& g : groups) {
    if (g.acc < retain) break;
    if (std::find(seen.begin(), seen.end(), g.best_slot) != seen.end()) continue;
    seen.push_back(g.best_slot);
    r.candidates.push_back({idAt(g.best_slot), g.acc, g.best / std::max(min_score, 1e-9)});
  }
  r.timings.push_back({"group", msSince(t)});
  r.status = QueryStatus::kFound;
  return r;
}

}  // namespace binloop
