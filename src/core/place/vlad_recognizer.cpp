#include "binloop/place/vlad_recognizer.h"

#include <algorithm>
#include <sstream>

#include "binloop/place/place_error.h"

namespace binloop {

VladRecognizer::VladRecognizer(std::shared_ptr<const VladVocabulary> voc, int reference_rank)
    : voc_(std::move(voc)), reference_rank_(checkedReferenceRank(reference_rank, "vlad")) {
  if (!voc_) throw PlaceError("vlad: no vocabulary");
}

std::shared_ptr<const VladVocabulary> VladRecognizer::loadVocabulary(const std::string& path,
                                                                     ModelType type) {
  ModelReader r(path);
  r.expectType(type);
  auto v = std::make_shared<VladVocabulary>(VladVocabulary::read(r));
  if (type != ModelType::kVladPq) r.expectEnd();
  return v;
}

void VladRecognizer::addSignature(Slot, const Descriptors& d) {
  sigs_.push(binarizeSigns(voc_->aggregate(d).back(), voc_->dims(), descriptorSeed(d)));
}

size_t VladRecognizer::indexBytesPerKeyframe() const { return sigs_.words() * sizeof(uint64_t); }

QueryResult VladRecognizer::querySignature(const SlotScope& scope) const {
  QueryResult r;
  const uint64_t* q = sigs_[scope.query];
  auto t = std::chrono::steady_clock::now();
  const size_t refs = scope.reference.size();
  const int bar = referenceBar(sigs_, scope.query, scope.reference, reference_rank_);
  const double cap = ranking().distance_cap * static_cast<double>(sigs_.words() * 64);
  r.threshold = bar;
  r.timings.push_back({"reference", msSince(t)});
  t = std::chrono::steady_clock::now();
  std::vector<Candidate> all;
  for (Slot k = 0; k < sigs_.size(); ++k) {
    if (scope.excluded[k]) continue;
    const int d = sigs_.distance(q, k);
    const Candidate c{idAt(k), -static_cast<double>(d), distanceConfidence(refs ? bar : 0, d, cap)};
    offer(r, c, refs && d < bar);
    if (scope.max_ranked) all.push_back(c);
  }
  sortCandidates(r);
  if (scope.max_ranked) keepRanked(r, std::move(all), scope.max_ranked);
  r.timings.push_back({"scan", msSince(t)});
  std::ostringstream detail;
  detail << "bar " << bar << " bits (" << referenceRankText(reference_rank_, refs) << "); "
         << r.candidates.size() << " closer";
  r.detail = detail.str();
  r.status = !refs                  ? QueryStatus::kNoReference
             : r.candidates.empty() ? QueryStatus::kBelowReference
                                    : QueryStatus::kFound;
  return r;
}

}  // namespace binloop
