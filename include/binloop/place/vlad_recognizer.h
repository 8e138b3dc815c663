#pragma once
// `vlad` (thesis 4.4, "Loop closure detection with VLAD"): binarized VLAD signatures compared by Hamming
// distance. The bar is the smallest distance between the query and its reference keyframes; every other
// keyframe closer than that is a candidate. No pre-filter: this is the thesis' baseline.
#include <memory>

#include "binloop/place/place_recognizer.h"
#include "binloop/place/signature_store.h"
#include "binloop/place/vlad_vocabulary.h"

namespace binloop {

class VladRecognizer : public PlaceRecognizer {
 public:
  explicit VladRecognizer(std::shared_ptr<const VladVocabulary> voc);
  static std::shared_ptr<const VladVocabulary> loadVocabulary(const std::string& path, ModelType type);
  std::string name() const override { return "vlad"; }
  size_t indexBytesPerKeyframe() const override;

 protected:
  void addSignature(Slot slot, const Descriptors& d) override;
  QueryResult querySignature(const SlotScope& scope) const override;

 private:
  std::shared_ptr<const VladVocabulary> voc_;
  SignatureStore sigs_;  // per slot
};

}  // namespace binloop
