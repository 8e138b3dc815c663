#include "binloop/place/signature_store.h"

#include <algorithm>
#include <string>

#include "binloop/place/place_error.h"

namespace binloop {

void SignatureStore::push(const BinarySignature& s) {
  if (s.empty()) throw PlaceError("signature store: empty signature");
  if (words_ == 0) words_ = s.size();
  if (s.size() != words_) {
    throw PlaceError("signature store: a signature of " + std::to_string(s.size()) + " words among ones of " +
                     std::to_string(words_));
  }
  data_.insert(data_.end(), s.begin(), s.end());
}

int checkedReferenceRank(int rank, const std::string& model) {
  if (rank < 1) throw PlaceError(model + ": reference rank " + std::to_string(rank) + ", must be at least 1");
  return rank;
}

std::string referenceRankText(int rank, size_t references) {
  if (static_cast<size_t>(rank) <= references)
    return "reference rank " + std::to_string(rank) + " of " + std::to_string(references);
  return "the farthest of " + std::to_string(references) + " references (rank " + std::to_string(rank) + ")";
}

int referenceBar(const SignatureStore& sigs, size_t q, const std::vector<uint32_t>& ref_slots, int rank) {
  if (ref_slots.empty()) return -1;
  std::vector<int> d;
  d.reserve(ref_slots.size());
  for (uint32_t k : ref_slots) d.push_back(sigs.distance(sigs[q], k));
  return rankedDistance(std::move(d), rank);
}

}  // namespace binloop
