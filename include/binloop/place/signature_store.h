#pragma once
// Binary signatures of one length, one after another in a single array, indexed by slot. A query scans
// them in slot order, so the hardware prefetcher streams them; kept as separate vectors each one was a heap
// block of its own and, once tracking and mapping had run between two queries, a cache miss of its own
// (vlad on rendered 00 in the SLAM: 0.18 ms per query over 1400 signatures of 16 words, against 0.028 ms
// in eval-loops, where the queries follow one another).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "binloop/place/vlad_vocabulary.h"

namespace binloop {

class SignatureStore {
 public:
  /// Throws PlaceError for a signature whose length differs from the first one's.
  void push(const BinarySignature& s);
  size_t size() const { return words_ ? data_.size() / words_ : 0; }
  bool empty() const { return data_.empty(); }
  size_t words() const { return words_; }
  const uint64_t* operator[](size_t slot) const { return data_.data() + slot * words_; }
  /// Hamming distance between two stored signatures, or between `q` (of words() words) and one.
  int distance(const uint64_t* q, size_t slot) const {
    const uint64_t* s = (*this)[slot];
    int d = 0;
    for (size_t i = 0; i < words_; ++i) d += __builtin_popcountll(q[i] ^ s[i]);
    return d;
  }

 private:
  std::vector<uint64_t> data_;
  size_t words_ = 0;
};

/// `rank` when it is at least 1 (the closest reference); otherwise throws PlaceError naming `model`. The
/// recognizers that take a rank check it once, when they are built.
int checkedReferenceRank(int rank, const std::string& model);

/// The `rank`-th smallest of `distances` (1: the smallest; a rank beyond their number counts as the
/// largest). `rank` is at least 1 (checkedReferenceRank) and `distances` not empty.
template <typename T>
T rankedDistance(std::vector<T> distances, int rank) {
  const auto nth =
      distances.begin() + std::min<std::ptrdiff_t>(rank, static_cast<std::ptrdiff_t>(distances.size())) - 1;
  std::nth_element(distances.begin(), nth, distances.end());
  return *nth;
}

/// The `rank`-th smallest Hamming distance from stored signature `q` to those of the reference slots
/// (rankedDistance), or -1 without references.
int referenceBar(const SignatureStore& sigs, size_t q, const std::vector<uint32_t>& ref_slots, int rank);
/// Which reference set the bar, for a query's detail: "reference rank 3 of 10", or "the farthest of 2
/// references (rank 3)" when there are fewer references than the rank.
std::string referenceRankText(int rank, size_t references);

}  // namespace binloop
