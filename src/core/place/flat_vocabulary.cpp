#include "binloop/place/flat_vocabulary.h"

#include <algorithm>
#include <string>

#include "binloop/place/k_majority.h"

namespace binloop {

FlatVocabulary FlatVocabulary::train(const std::vector<Descriptors>& images, const FlatVocabParams& p,
                                     const ProgressFn& progress) {
  size_t total = 0;
  for (const auto& im : images) total += im.size();
  if (p.words < 2) throw PlaceError("flat vocabulary needs at least 2 words");
  if (total < static_cast<size_t>(p.words) * 5) {
    throw PlaceError("too few descriptors for a " + std::to_string(p.words) + "-word flat vocabulary: " +
                     std::to_string(total) + " (need at least " + std::to_string(p.words * 5) + ")");
  }
  const size_t stride =
      std::max<size_t>(1, (total + p.max_training_descriptors - 1) / p.max_training_descriptors);
  Descriptors data;
  size_t seen = 0;
  for (const auto& im : images) {
    for (const auto& d : im)
      if (seen++ % stride == 0) data.push_back(d);
  }
  std::vector<uint32_t> idx(data.size());
  for (size_t i = 0; i < idx.size(); ++i) idx[i] = static_cast<uint32_t>(i);
  if (progress) progress(0, 1);
  KMajorityResult km = kMajority(data, idx, {p.words, p.max_iterations, p.seed});
  if (progress) progress(1, 1);
  if (km.centres.size() < static_cast<size_t>(p.words) * 9 / 10) {
    throw PlaceError("degenerate flat vocabulary: " + std::to_string(km.centres.size()) +
                     " non-empty words of " + std::to_string(p.words) + " requested (" +
                     std::to_string(km.dropped_empty) + " empty clusters)");
  }
  return FlatVocabulary(std::move(km.centres));
}

std::vector<uint32_t> FlatVocabulary::presence(const Descriptors& d) const {
  std::vector<uint32_t> w;
  w.reserve(d.size());
  for (const auto& x : d) w.push_back(nearestCentre(x, words_.data(), words_.size()));
  std::sort(w.begin(), w.end());
  w.erase(std::unique(w.begin(), w.end()), w.end());
  return w;
}

}  // namespace binloop
