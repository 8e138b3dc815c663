#include "binloop/place/vlad_recognizer.h"

#include <algorithm>
#include <sstream>

#include "binloop/place/place_error.h"

namespace binloop {

int closestReference(const BinarySignature& q, const std::vector<KeyframeId>& refs,
                     const std::unordered_map<KeyframeId, BinarySignature>& sigs, int* count) {
  int best = -1, n = 0;
  for (KeyframeId k : refs) {
    const auto it = sigs.find(k);
    if (it == sigs.end()) continue;
    const int d = hammingBits(q, it->second);
    if (best < 0 || d < best) best = d;
    ++n;
  }
  if (count) *count = n;
  return best;
}

VladRecognizer::VladRecognizer(std::shared_ptr<const VladVocabulary> voc) : voc_(std::move(voc)) {
  if (!voc_) throw PlaceError("vlad: no vocabulary");
}

std::shared_ptr<const VladVocabulary> VladRecognizer::loadVocabulary(const std::string& path, ModelType type) {
  ModelReader r(path);
  r.expectType(type);
  auto v = std::make_shared<VladVocabulary>(VladVocabulary::read(r));
  if (type != ModelType::kVladPq) r.expectEnd();
  return v;
}

void VladRecognizer::addSignature(KeyframeId id, const Descriptors& d) {
  auto levels = voc_->aggregate(d);
  auto& s = sigs_[id] = binarizeSigns(levels.back());
  scan_.emplace_back(id, &s);
}

size_t VladRecognizer::indexBytesPerKeyframe() const {
  return sigs_.empty() ? 0 : sigs_.begin()->second.size() * sizeof(uint64_t) + sizeof(KeyframeId);
}

QueryResult VladRecognizer::querySignature(KeyframeId id, const QueryScope& scope,
                                           const std::function<bool(KeyframeId)>& excluded) const {
  QueryResult r;
  const BinarySignature& q = sigs_.at(id);
  auto t = std::chrono::steady_clock::now();
  int refs = 0;
  const int bar = closestReference(q, scope.reference, sigs_, &refs);
  r.threshold = bar;
  r.timings.push_back({"reference", msSince(t)});
  t = std::chrono::steady_clock::now();
  for (const auto& [k, s] : scan_) {
    if (excluded(k)) continue;
    const int d = hammingBits(q, *s);
    const Candidate c{k, -static_cast<double>(d), distanceConfidence(refs ? bar : 0, d)};
    offer(r, c, refs && d < bar);
  }
  sortCandidates(r);
  r.timings.push_back({"scan", msSince(t)});
  std::ostringstream detail;
  detail << "bar " << bar << " bits from " << refs << " reference keyframes; " << r.candidates.size() << " closer";
  r.detail = detail.str();
  r.status = !refs ? QueryStatus::kNoReference : r.candidates.empty() ? QueryStatus::kBelowReference : QueryStatus::kFound;
  return r;
}

}  // namespace binloop
