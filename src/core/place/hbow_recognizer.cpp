#include "binloop/place/hbow_recognizer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "binloop/place/place_error.h"

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
  for (const auto& e : b) inverted_[e.word].push_back({slot, e.value});
  bows_.push_back(std::move(b));
}

std::vector<uint32_t> HbowRecognizer::matchWords(const Descriptors& d) const {
  std::vector<uint32_t> w(d.size());
  for (size_t i = 0; i < d.size(); ++i) w[i] = voc_->nodeOf(d[i], 2);
  return w;
}

size_t HbowRecognizer::indexBytesPerKeyframe() const {
  if (bows_.empty()) return 0;
  size_t entries = 0;
  for (const auto& b : bows_) entries += b.size();
  // BoW entry (word + weight) and one inverted-index entry (slot + weight) per word of each keyframe.
  return entries * (sizeof(BowEntry) + sizeof(Posting)) / bows_.size();
}

// The score `ranking().score_background_quantile` of the keyframes outside the scope stay below (those
// sharing no word score 0): the level a match must stand out from to rank high.
double HbowRecognizer::background(const std::vector<double>& score, const std::vector<char>& excluded) const {
  std::vector<double> v;
  v.reserve(score.size());
  for (size_t k = 0; k < score.size(); ++k) {
    if (!excluded[k]) v.push_back(score[k]);
  }
  if (v.empty()) return 0;
  const auto nth = v.begin() + static_cast<std::ptrdiff_t>(ranking().score_background_quantile *
                                                           static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), nth, v.end());
  return *nth;
}

// One pass over the query's inverted lists gives every keyframe's common-word count and its L1 score:
// DBoW2's score 1 - |a - b|_1 / 2 of L1-normalised vectors is sum over common words of
// (|a_w| + |b_w| - |a_w - b_w|) / 2, and words that only one vector has add nothing. Returns the keyframes
// that share a word, in slot order.
std::vector<HbowRecognizer::Slot> HbowRecognizer::scoreAll(const BowVector& q, std::vector<uint32_t>* common,
                                                           std::vector<double>* score) const {
  std::vector<Slot> touched;
  for (const auto& e : q) {
    const double a = e.value;
    for (const Posting& p : inverted_[e.word]) {
      if ((*common)[p.slot]++ == 0) touched.push_back(p.slot);
      (*score)[p.slot] += 0.5 * (std::fabs(a) + std::fabs(p.weight) - std::fabs(a - p.weight));
    }
  }
  std::sort(touched.begin(), touched.end());  // results never depend on the order lists came in
  return touched;
}

QueryResult HbowRecognizer::querySignature(const SlotScope& scope) const {
  QueryResult r;
  const BowVector& q = bows_[scope.query];
  auto t = std::chrono::steady_clock::now();
  std::vector<uint32_t> common(bows_.size(), 0);
  std::vector<double> score(bows_.size(), 0);
  const std::vector<Slot> touched = scoreAll(q, &common, &score);
  r.timings.push_back({"inverted_index", msSince(t)});

  t = std::chrono::steady_clock::now();
  double min_score = std::numeric_limits<double>::max();
  for (Slot k : scope.reference) min_score = std::min(min_score, score[k]);
  const size_t refs = scope.reference.size();
  if (refs == 0) {
    r.status = QueryStatus::kNoReference;
    r.detail =
        "none of the " + std::to_string(scope.reference_named) + " reference keyframes is in the database";
    return r;
  }
  const double reference_score = min_score;
  min_score = std::max(min_score, min_bar_);
  r.threshold = min_score;
  size_t sharing = 0;
  uint32_t max_common = 0;
  for (Slot k : touched) {
    if (scope.excluded[k]) continue;
    ++sharing;
    max_common = std::max(max_common, common[k]);
  }
  const uint32_t min_common = static_cast<uint32_t>(0.8f * max_common);
  const double rank_bar = std::max(min_score, background(score, scope.excluded));
  auto confidence = [&](double s) { return scoreConfidence(s, rank_bar, ranking().score_floor); };
  if (scope.max_ranked > 0) {
    std::vector<Candidate> all;
    for (Slot k : touched) {
      if (!scope.excluded[k]) all.push_back({idAt(k), score[k], confidence(score[k])});
    }
    keepRanked(r, std::move(all), scope.max_ranked);
  }
  if (sharing == 0) {
    r.status = QueryStatus::kNoPreCandidates;
    r.detail = "no keyframe outside the scope shares a word with the query";
    r.timings.push_back({"select", msSince(t)});
    return r;
  }
  std::vector<Slot> scored;
  for (Slot k : touched) {
    if (scope.excluded[k]) continue;
    if (common[k] > min_common && score[k] >= min_score) {
      scored.push_back(k);
    } else {
      offer(r, {idAt(k), score[k], confidence(score[k])}, false);
    }
  }
  // Only keyframes that reached the bar take part in group accumulation (-1: did not).
  std::vector<double> passed(bows_.size(), -1);
  for (Slot k : scored) passed[k] = score[k];
  r.timings.push_back({"select", msSince(t)});
  std::ostringstream detail;
  detail << "bar " << min_score;
  if (reference_score < min_score) detail << " (floor; the references scored " << reference_score << ")";
  detail << " from " << refs << " reference keyframes; " << sharing << " share words (max " << max_common
         << "); " << scored.size() << " reach the bar";
  r.detail = detail.str();
  if (scored.empty()) {
    r.status = QueryStatus::kBelowReference;
    return r;
  }

  accumulateGroups(scored, passed, rank_bar, &r);
  r.status = QueryStatus::kFound;
  return r;
}

// Groups of covisible keyframes that reached the bar (DBoW2's islands): each scored keyframe with its group's
// passed scores summed; groups within 75 % of the best give their best keyframe as a candidate.
void HbowRecognizer::accumulateGroups(const std::vector<Slot>& scored, const std::vector<double>& passed,
                                      double rank_bar, QueryResult* r) const {
  const auto t = std::chrono::steady_clock::now();
  struct Group {
    double acc, best;
    Slot best_slot;
  };
  std::vector<Group> groups;
  double best_acc = 0;
  for (Slot k : scored) {
    Group g{passed[k], passed[k], k};
    for (KeyframeId n : group(idAt(k))) {
      Slot ns;
      if (!findSlot(n, &ns) || passed[ns] < 0) continue;
      g.acc += passed[ns];
      if (passed[ns] > g.best) g.best = passed[ns], g.best_slot = ns;
    }
    best_acc = std::max(best_acc, g.acc);
    groups.push_back(g);
  }
  std::stable_sort(groups.begin(), groups.end(),
                   [](const Group& a, const Group& b) { return a.acc > b.acc; });
  const double retain = 0.75 * best_acc;
  std::vector<Slot> seen;
  for (const Group& g : groups) {
    if (g.acc < retain) break;
    if (std::find(seen.begin(), seen.end(), g.best_slot) != seen.end()) continue;
    seen.push_back(g.best_slot);
    r->candidates.push_back(
        {idAt(g.best_slot), g.acc, scoreConfidence(g.best, rank_bar, ranking().score_floor)});
  }
  r->timings.push_back({"group", msSince(t)});
}

}  // namespace binloop
