#pragma once
// `hmvlad` (thesis 4.2 and "Loop closure detection with HMVLAD"): one binarized VLAD per level of a
// vocabulary tree. The short (first-level) signature rejects: only keyframes closer than every reference
// keyframe in short bits go on. The long (last-level) signature verifies the same way.
#include <memory>
#include <unordered_map>

#include "binloop/place/place_recognizer.h"
#include "binloop/place/vlad_vocabulary.h"

namespace binloop {

class HmvladRecognizer : public PlaceRecognizer {
 public:
  explicit HmvladRecognizer(std::shared_ptr<const VladVocabulary> voc);
  std::string name() const override { return "hmvlad"; }
  size_t indexBytesPerKeyframe() const override;

 protected:
  void addSignature(KeyframeId id, const Descriptors& d) override;
  QueryResult querySignature(KeyframeId id, const QueryScope& scope,
                             const std::function<bool(KeyframeId)>& excluded) const override;

 private:
  std::shared_ptr<const VladVocabulary> voc_;
  std::unordered_map<KeyframeId, BinarySignature> short_, long_;
  std::vector<std::pair<KeyframeId, const BinarySignature*>> scan_;  // short signatures in insertion order
};

}  // namespace binloop
