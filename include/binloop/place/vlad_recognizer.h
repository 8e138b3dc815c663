#pragma once
// `vlad` (thesis 4.4, "Loop closure detection with VLAD"): binarized VLAD signatures compared by Hamming
// distance. The bar is the smallest distance between the query and its reference keyframes; every other
// keyframe closer than that is a candidate. No pre-filter: this is the thesis' baseline.
#include <memory>
#include <unordered_map>

#include "binloop/place/place_recognizer.h"
#include "binloop/place/vlad_vocabulary.h"

namespace binloop {

/// Smallest Hamming distance from `q` to the signatures of the known reference keyframes, or -1.
int closestReference(const BinarySignature& q, const std::vector<KeyframeId>& refs,
                     const std::unordered_map<KeyframeId, BinarySignature>& sigs, int* count = nullptr);
/// Confidence of a distance against a bar: bar / distance (>= 1 when it beats the bar).
inline double distanceConfidence(double bar, double dist) { return (bar + 1.0) / (dist + 1.0); }

class VladRecognizer : public PlaceRecognizer {
 public:
  explicit VladRecognizer(std::shared_ptr<const VladVocabulary> voc);
  static std::shared_ptr<const VladVocabulary> loadVocabulary(const std::string& path, ModelType type);
  std::string name() const override { return "vlad"; }
  size_t indexBytesPerKeyframe() const override;

 protected:
  void addSignature(KeyframeId id, const Descriptors& d) override;
  QueryResult querySignature(KeyframeId id, const QueryScope& scope,
                             const std::function<bool(KeyframeId)>& excluded) const override;

 private:
  std::shared_ptr<const VladVocabulary> voc_;
  std::unordered_map<KeyframeId, BinarySignature> sigs_;
  std::vector<std::pair<KeyframeId, const BinarySignature*>> scan_;  // insertion order, for a linear scan
};

}  // namespace binloop
