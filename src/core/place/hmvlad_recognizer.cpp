#include "binloop/place/hmvlad_recognizer.h"

#include <algorithm>
#include <sstream>

#include "binloop/place/place_error.h"
#include "binloop/place/vlad_recognizer.h"
#include "binloop/util/hash_random.h"

namespace binloop {

HmvladRecognizer::HmvladRecognizer(std::shared_ptr<const VladVocabulary> voc, int reference_rank)
    : voc_(std::move(voc)), reference_rank_(checkedReferenceRank(reference_rank, "hmvlad")) {
  if (!voc_) throw PlaceError("hmvlad: no vocabulary");
  if (voc_->levels() < 2) throw PlaceError("hmvlad needs a vocabulary of at least 2 levels, this one has 1");
}

void HmvladRecognizer::addSignature(Slot, const Descriptors& d) {
  const auto levels = voc_->aggregate(d);
  const uint64_t seed = descriptorSeed(d);
  short_.push(binarizeSigns(levels.front(), voc_->dims(), seed));
  long_.push(binarizeSigns(levels.back(), voc_->dims(), hashCombine(seed, 1)));
}

size_t HmvladRecognizer::indexBytesPerKeyframe() const {
  if (short_.empty()) return 0;
  return (short_.words() + long_.words()) * sizeof(uint64_t);
}

QueryResult HmvladRecognizer::querySignature(const SlotScope& scope) const {
  QueryResult r;
  const uint64_t* qs = short_[scope.query];
  const uint64_t* ql = long_[scope.query];
  auto t = std::chrono::steady_clock::now();
  const size_t refs = scope.reference.size();
  const int bar_short = referenceBar(short_, scope.query, scope.reference, reference_rank_);
  const int bar_long = referenceBar(long_, scope.query, scope.reference, reference_rank_);
  const double cap = ranking().distance_cap * static_cast<double>(long_.words() * 64);
  r.threshold = bar_long;
  r.timings.push_back({"reference", msSince(t)});
  if (!refs) {
    r.status = QueryStatus::kNoReference;
    r.detail = "no reference keyframe in the database";
    return r;
  }
  t = std::chrono::steady_clock::now();
  std::vector<Slot> pre;
  int closest_short = -1;  // the keyframe nearest by the short signature, verified even when it fails it
  int closest_short_d = 0;
  for (Slot k = 0; k < short_.size(); ++k) {
    if (scope.excluded[k]) continue;
    const int d = short_.distance(qs, k);
    if (d < bar_short) pre.push_back(k);
    if (closest_short < 0 || d < closest_short_d) closest_short = static_cast<int>(k), closest_short_d = d;
  }
  r.timings.push_back({"short_reject", msSince(t)});
  t = std::chrono::steady_clock::now();
  for (Slot k : pre) {
    const int d = long_.distance(ql, k);
    const Candidate c{idAt(k), -static_cast<double>(d), distanceConfidence(bar_long, d, cap)};
    offer(r, c, d < bar_long);
  }
  if (closest_short >= 0 && closest_short_d >= bar_short) {
    // Nothing passed the short signature, or this one did not: it still stands as the best rejected, so
    // that a query always names the model's nearest keyframe.
    const int d = long_.distance(ql, static_cast<size_t>(closest_short));
    offer(r, {idAt(closest_short), -static_cast<double>(d), distanceConfidence(bar_long, d, cap)}, false);
  }
  sortCandidates(r);
  if (scope.max_ranked) {
    std::vector<Candidate> all;
    for (Slot k = 0; k < long_.size(); ++k) {
      if (scope.excluded[k]) continue;
      const int d = long_.distance(ql, k);
      all.push_back({idAt(k), -static_cast<double>(d), distanceConfidence(bar_long, d, cap)});
    }
    keepRanked(r, std::move(all), scope.max_ranked);
  }
  r.timings.push_back({"long_verify", msSince(t)});
  std::ostringstream detail;
  detail << "bars " << bar_short << "/" << bar_long << " bits (short/long; "
         << referenceRankText(reference_rank_, refs) << "); " << pre.size() << " pass the short signature, "
         << r.candidates.size() << " the long";
  r.detail = detail.str();
  r.status = pre.empty()            ? QueryStatus::kNoPreCandidates
             : r.candidates.empty() ? QueryStatus::kBelowReference
                                    : QueryStatus::kFound;
  return r;
}

}  // namespace binloop
