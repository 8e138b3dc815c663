#pragma once
// `hmvlad` (thesis 4.2 and "Loop closure detection with HMVLAD"): one binarized VLAD per level of a
// vocabulary tree. The short (first-level) signature rejects: only keyframes closer than every reference
// keyframe in short bits go on. The long (last-level) signature verifies the same way.
#include <memory>

#include "binloop/place/place_recognizer.h"
#include "binloop/place/signature_store.h"
#include "binloop/place/vlad_vocabulary.h"

namespace binloop {

class HmvladRecognizer : public PlaceRecognizer {
 public:
  explicit HmvladRecognizer(std::shared_ptr<const VladVocabulary> voc);
  std::string name() const override { return "hmvlad"; }
  size_t indexBytesPerKeyframe() const override;

 protected:
  void addSignature(Slot slot, const Descriptors& d) override;
  QueryResult querySignature(const SlotScope& scope) const override;

 private:
  std::shared_ptr<const VladVocabulary> voc_;
  SignatureStore short_, long_;  // per slot
};

}  // namespace binloop
