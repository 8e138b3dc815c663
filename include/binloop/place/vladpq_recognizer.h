#pragma once
// `vladpq` (thesis 4.3 and "Loop closure detection with VLAD+PQ"): each keyframe's VLAD is also product
// quantized into one code per word, and (word, code) pairs go into an inverted index. Keyframes that share
// as many pairs as the best reference keyframe less a slack (default 8 of 64 words, at least one pair) are
// pre-candidates (the thesis asks for strictly more; with the thesis' 4 words the best reference usually
// shares all 4, so strictly more would never pass, and even "as many" keeps out revisits the VLAD ranks
// first — see ARCHITECTURE notes); they are verified like `vlad`, by binarized-VLAD Hamming distance below
// the third closest reference (`reference_rank`, as vlad's), or by SDC/ADC distance when chosen.
#include <memory>

#include "binloop/place/place_recognizer.h"
#include "binloop/place/pq_codebooks.h"
#include "binloop/place/signature_store.h"
#include "binloop/place/vlad_vocabulary.h"

namespace binloop {

enum class PqVerify { kHamming, kSdc, kAdc };

struct VladPqModel {
  std::shared_ptr<const VladVocabulary> vlad;
  std::shared_ptr<const PqCodebooks> pq;
  static VladPqModel load(const std::string& path);
};

class VladPqRecognizer : public PlaceRecognizer {
 public:
  /// `shared_slack`: a pre-candidate may share this many (word, code) pairs fewer than the best reference
  /// (never fewer than one). `reference_rank`: the verification bar is the distance to the rank-th closest
  /// reference (1: the closest, the thesis'), as vlad's. Throws PlaceError when the slack is negative or the
  /// rank below 1.
  VladPqRecognizer(VladPqModel model, PqVerify verify, int shared_slack, int reference_rank);
  std::string name() const override { return "vladpq"; }
  size_t indexBytesPerKeyframe() const override;

 protected:
  void addSignature(Slot slot, const Descriptors& d) override;
  QueryResult querySignature(const SlotScope& scope) const override;

 private:
  VladPqModel model_;
  PqVerify verify_;
  uint32_t shared_slack_;
  int reference_rank_;
  // Per slot:
  SignatureStore sigs_;
  std::vector<PqCodes> codes_;
  std::vector<std::vector<float>> raw_;      // only kept for ADC
  std::vector<std::vector<char>> empty_;     // per word: no descriptor fell into it (its code says nothing)
  std::vector<std::vector<Slot>> inverted_;  // per (word, code); empty words are left out
  double distance(Slot q, Slot k) const;
};

}  // namespace binloop
