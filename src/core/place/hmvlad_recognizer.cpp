#include "binloop/place/hmvlad_recognizer.h"

#include <algorithm>
#include <sstream>

#include "binloop/place/place_error.h"
#include "binloop/place/vlad_recognizer.h"

namespace binloop {

HmvladRecognizer::HmvladRecognizer(std::shared_ptr<const VladVocabulary> voc) : voc_(std::move(voc)) {
  if (!voc_) throw PlaceError("hmvlad: no vocabulary");
  if (voc_->levels() < 2) throw PlaceError("hmvlad needs a vocabulary of at least 2 levels, this one has 1");
}

void HmvladRecognizer::addSignature(KeyframeId id, const Descriptors& d) {
  const auto levels = voc_->aggregate(d);
  auto& s = short_[id] = binarizeSigns(levels.front());
  long_[id] = binarizeSigns(levels.back());
  scan_.emplace_back(id, &s);
}

size_t HmvladRecognizer::indexBytesPerKeyframe() const {
  if (short_.empty()) return 0;
  return (short_.begin()->second.size() + long_.begin()->second.size()) * sizeof(uint64_t) + sizeof(KeyframeId);
}

QueryResult HmvladRecognizer::querySignature(KeyframeId id, const QueryScope& scope,
                                             const std::function<bool(KeyframeId)>& excluded) const {
  QueryResult r;
  const BinarySignature& qs = short_.at(id);
  const BinarySignature& ql = long_.at(id);
  auto t = std::chrono::steady_clock::now();
  int refs = 0;
  const int bar_short = closestReference(qs, scope.reference, short_, &refs);
  const int bar_long = closestReference(ql, scope.reference, long_);
  r.threshold = bar_long;
  r.timings.push_back({"reference", msSince(t)});
  if (!refs) {
    r.status = QueryStatus::kNoReference;
    r.detail = "no reference keyframe in the database";
    return r;
  }
  t = std::chrono::steady_clock::now();
  std::vector<KeyframeId> pre;
  for (const auto& [k, s] : scan_)
    if (!excluded(k) && hammingBits(qs, *s) < bar_short) pre.push_back(k);
  r.timings.push_back({"short_reject", msSince(t)});
  t = std::chrono::steady_clock::now();
  for (KeyframeId k : pre) {
    const int d = hammingBits(ql, long_.at(k));
    const Candidate c{k, -static_cast<double>(d), distanceConfidence(bar_long, d)};
    offer(r, c, d < bar_long);
  }
  sortCandidates(r);
  r.timings.push_back({"long_verify", msSince(t)});
  std::ostringstream detail;
  detail << "bars " << bar_short << "/" << bar_long << " bits (short/long) from " << refs << " reference keyframes; "
         << pre.size() << " pass the short signature, " << r.candidates.size() << " the long";
  r.detail = detail.str();
  r.status = pre.empty() ? QueryStatus::kNoPreCandidates
             : r.candidates.empty() ? QueryStatus::kBelowReference : QueryStatus::kFound;
  return r;
}

}  // namespace binloop
