#include "binloop/place/signature_store.h"

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

int closestReference(const SignatureStore& sigs, size_t q, const std::vector<uint32_t>& ref_slots) {
  int best = -1;
  for (uint32_t k : ref_slots) {
    const int d = sigs.distance(sigs[q], k);
    if (best < 0 || d < best) best = d;
  }
  return best;
}

}  // namespace binloop
