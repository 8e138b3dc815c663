#include "binloop/place/vladpq_recognizer.h"

#include <algorithm>
#include <limits>
#include <sstream>
#include <string>

#include "binloop/place/place_error.h"
#include "binloop/place/slot_counter.h"
#include "binloop/place/vlad_recognizer.h"

namespace binloop {

VladPqModel VladPqModel::load(const std::string& path) {
  ModelReader r(path);
  r.expectType(ModelType::kVladPq);
  VladPqModel m;
  m.vlad = std::make_shared<VladVocabulary>(VladVocabulary::read(r));
  m.pq = std::make_shared<PqCodebooks>(PqCodebooks::read(r));
  r.expectEnd();
  if (m.pq->words() != m.vlad->wordsAtLevel(m.vlad->levels()) || m.pq->dims() != m.vlad->dims())
    throw PlaceError(path + ": PQ codebooks do not fit the VLAD vocabulary");
  return m;
}

namespace {

uint32_t checkedSlack(int slack) {
  if (slack < 0) throw PlaceError("vladpq: shared slack " + std::to_string(slack) + " < 0");
  return static_cast<uint32_t>(slack);
}

}  // namespace

VladPqRecognizer::VladPqRecognizer(VladPqModel model, PqVerify verify, int shared_slack, int reference_rank)
    : model_(std::move(model)),
      verify_(verify),
      shared_slack_(checkedSlack(shared_slack)),
      reference_rank_(checkedReferenceRank(reference_rank, "vladpq")) {
  if (!model_.vlad || !model_.pq) throw PlaceError("vladpq: no model");
  inverted_.resize(static_cast<size_t>(model_.pq->words()) * model_.pq->m());
}

void VladPqRecognizer::addSignature(Slot slot, const Descriptors& d) {
  auto v = model_.vlad->aggregate(d).back();
  sigs_.push(binarizeSigns(v, model_.vlad->dims(), descriptorSeed(d)));
  PqCodes codes = model_.pq->encode(v);
  codes_.push_back(std::move(codes));
  const PqCodes& c = codes_.back();
  // An empty word's sub-vector is all zero and encodes to the same code in every image: two images with few
  // features would share it (as their sign bits would agree, binarizeSigns), so it is not indexed.
  std::vector<char> empty = emptyWords(v, model_.pq->dims());
  for (int w = 0; w < model_.pq->words(); ++w)
    if (!empty[w]) inverted_[static_cast<size_t>(w) * model_.pq->m() + c[w]].push_back(slot);
  empty_.push_back(std::move(empty));
  raw_.push_back(verify_ == PqVerify::kAdc ? std::move(v) : std::vector<float>{});
}

size_t VladPqRecognizer::indexBytesPerKeyframe() const {
  if (sigs_.empty()) return 0;
  const size_t words = static_cast<size_t>(model_.pq->words());
  size_t b = sigs_.words() * sizeof(uint64_t) + words * (sizeof(uint16_t) + sizeof(Slot));
  if (verify_ == PqVerify::kAdc) b += words * model_.pq->dims() * sizeof(float);
  return b;
}

double VladPqRecognizer::distance(Slot q, Slot k) const {
  switch (verify_) {
    case PqVerify::kHamming:
      return sigs_.distance(sigs_[q], k);
    case PqVerify::kSdc:
      return model_.pq->sdc(codes_[q], codes_[k]);
    case PqVerify::kAdc:
      return model_.pq->adc(raw_[q], codes_[k]);
  }
  return 0;
}

QueryResult VladPqRecognizer::querySignature(const SlotScope& scope) const {
  QueryResult r;
  const Slot id = scope.query;
  const PqCodes& qc = codes_[id];
  auto t = std::chrono::steady_clock::now();
  SlotCounter shared(sigs_.size());
  for (int w = 0; w < model_.pq->words(); ++w)
    if (!empty_[id][w]) shared.add(inverted_[static_cast<size_t>(w) * model_.pq->m() + qc[w]]);
  const std::vector<Slot>& touched = shared.touched();  // the query itself too; scope.excluded drops it
  r.timings.push_back({"inverted_index", msSince(t)});
  t = std::chrono::steady_clock::now();
  const size_t refs = scope.reference.size();
  uint32_t max_ref_shared = 0;
  std::vector<double> ref_distance;
  ref_distance.reserve(refs);
  for (Slot k : scope.reference) {
    max_ref_shared = std::max(max_ref_shared, shared[k]);
    ref_distance.push_back(distance(id, k));
  }
  // The bar that admits: the rank-th closest reference's distance (rankedDistance). The bar that ranks
  // across queries stays the closest reference's: measured against the third, R@100P on rendered 00 fell
  // from 0.187 to 0.137 (docs/decisions.md); within a query both order candidates alike.
  double bar = std::numeric_limits<double>::max(), rank_bar = bar;
  if (refs) {
    bar = rankedDistance(ref_distance, reference_rank_);
    rank_bar = rankedDistance(ref_distance, 1);
  }
  r.timings.push_back({"reference", msSince(t)});
  if (!refs) {
    r.status = QueryStatus::kNoReference;
    r.detail = "no reference keyframe in the database";
    return r;
  }
  r.threshold = bar;
  // The cap is in the verification distance's units: bits for Hamming; SDC/ADC distances are not capped.
  const double cap = verify_ == PqVerify::kHamming
                         ? ranking().distance_cap * static_cast<double>(sigs_.words() * 64)
                         : std::numeric_limits<double>::max();
  t = std::chrono::steady_clock::now();
  size_t pre = 0;
  std::vector<Candidate> all;
  int most_shared = -1;  // the keyframe sharing most pairs among those the pre-filter drops
  const uint32_t min_shared = max_ref_shared > shared_slack_ + 1 ? max_ref_shared - shared_slack_ : 1;
  for (Slot k : touched) {
    if (scope.excluded[k]) continue;
    if (shared[k] < min_shared) {
      if (most_shared < 0 || shared[k] > shared[most_shared]) most_shared = static_cast<int>(k);
      continue;
    }
    ++pre;
    const double d = distance(id, k);
    const Candidate c{idAt(k), -d, distanceConfidence(rank_bar, d, cap)};
    offer(r, c, d < bar);
    if (scope.max_ranked) all.push_back(c);
  }
  if (most_shared >= 0 && !r.has_best_rejected && r.candidates.empty()) {
    // Nothing passed the pre-filter: the keyframe closest to passing stands as the best rejected.
    const double d = distance(id, most_shared);
    offer(r, {idAt(most_shared), -d, distanceConfidence(rank_bar, d, cap)}, false);
  }
  sortCandidates(r);
  if (scope.max_ranked) keepRanked(r, std::move(all), scope.max_ranked);
  r.timings.push_back({"verify", msSince(t)});
  std::ostringstream detail;
  detail << "references share up to " << max_ref_shared << " (word, code) pairs, bar " << bar << " ("
         << referenceRankText(reference_rank_, refs) << "); " << pre << " pre-candidates, "
         << r.candidates.size() << " verified";
  r.detail = detail.str();
  r.status = pre == 0               ? QueryStatus::kNoPreCandidates
             : r.candidates.empty() ? QueryStatus::kBelowReference
                                    : QueryStatus::kFound;
  return r;
}

}  // namespace binloop
