#pragma once
// `hmvlad` (thesis 4.2 and "Loop closure detection with HMVLAD"): one binarized VLAD per level of a
// vocabulary tree. The short (first-level) signature rejects: only keyframes closer in short bits than the
// `reference_rank`-th closest reference keyframe (the thesis: the closest, rank 1) go on. The long
// (last-level) signature verifies the same way.
#include <memory>

#include "binloop/place/place_recognizer.h"
#include "binloop/place/signature_store.h"
#include "binloop/place/vlad_vocabulary.h"

namespace binloop {

class HmvladRecognizer : public PlaceRecognizer {
 public:
  /// Throws PlaceError without a vocabulary of 2+ levels or for a reference rank below 1.
  explicit HmvladRecognizer(std::shared_ptr<const VladVocabulary> voc, int reference_rank);
  std::string name() const override { return "hmvlad"; }
  size_t indexBytesPerKeyframe() const override;

 protected:
  void addSignature(Slot slot, const Descriptors& d) override;
  QueryResult querySignature(const SlotScope& scope) const override;

 private:
  std::shared_ptr<const VladVocabulary> voc_;
  SignatureStore short_, long_;  // per slot
  int reference_rank_;
};

}  // namespace binloop
