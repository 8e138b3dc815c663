#pragma once
// `vlad` (thesis 4.4, "Loop closure detection with VLAD"): binarized VLAD signatures compared by Hamming
// distance. The bar is the distance between the query and its `reference_rank`-th closest reference keyframe
// (the thesis: the closest, rank 1); every other keyframe closer than that is a candidate. No pre-filter:
// this is the thesis' baseline.
#include <memory>

#include "binloop/place/place_recognizer.h"
#include "binloop/place/signature_store.h"
#include "binloop/place/vlad_vocabulary.h"

namespace binloop {

class VladRecognizer : public PlaceRecognizer {
 public:
  /// Throws PlaceError without a vocabulary or for a reference rank below 1.
  explicit VladRecognizer(std::shared_ptr<const VladVocabulary> voc, int reference_rank);
  static std::shared_ptr<const VladVocabulary> loadVocabulary(const std::string& path, ModelType type);
  std::string name() const override { return "vlad"; }
  size_t indexBytesPerKeyframe() const override;

 protected:
  void addSignature(Slot slot, const Descriptors& d) override;
  QueryResult querySignature(const SlotScope& scope) const override;

 private:
  std::shared_ptr<const VladVocabulary> voc_;
  SignatureStore sigs_;  // per slot
  int reference_rank_;
};

}  // namespace binloop
