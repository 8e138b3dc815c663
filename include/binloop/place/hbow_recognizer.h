#pragma once
// `hbow`: ORB-SLAM2's keyframe database on a vocabulary tree. A query (1) sets the bar to the lowest L1
// score between the query and its reference keyframes, (2) counts common words with every other keyframe
// through the inverted index and keeps those with more than 80 % of the best count, (3) keeps those that
// score at least the bar, (4) accumulates each survivor's score with its group's and returns the best
// keyframe of every group whose sum reaches 75 % of the best sum.
//
// One addition to ORB-SLAM2: the bar never goes below `min_bar`. A view with no stable structure (open
// ground, sky, motion blur) shares almost no words even with its own neighbours; a bar near 0 would let
// any keyframe through with a huge score/bar confidence. ORB-SLAM2 never meets this because its
// covisible neighbours share map points, hence words, by construction.
#include <memory>

#include "binloop/place/place_recognizer.h"
#include "binloop/place/vocabulary_tree.h"

namespace binloop {

class HbowRecognizer : public PlaceRecognizer {
 public:
  explicit HbowRecognizer(std::shared_ptr<const VocabularyTree> voc, double min_bar = 0.005);
  static std::shared_ptr<const VocabularyTree> loadVocabulary(const std::string& path);
  std::string name() const override { return "hbow"; }
  size_t indexBytesPerKeyframe() const override;
  /// The tree's node 2 levels below the root (ORB-SLAM2 matches within the node 4 levels above the words
  /// of its 6-level vocabulary, the same cells).
  std::vector<uint32_t> matchWords(const Descriptors& d) const override;
  const BowVector& bow(KeyframeId id) const { return bows_[slotOf(id)]; }

 protected:
  void addSignature(Slot slot, const Descriptors& d) override;
  QueryResult querySignature(const SlotScope& scope) const override;

 private:
  std::vector<Slot> scoreAll(const BowVector& q, std::vector<uint32_t>* common,
                             std::vector<double>* score) const;
  double background(const std::vector<double>& score, const std::vector<char>& excluded) const;
  void accumulateGroups(const std::vector<Slot>& scored, const std::vector<double>& passed, double rank_bar,
                        QueryResult* r) const;
  std::shared_ptr<const VocabularyTree> voc_;
  double min_bar_;
  /// One inverted-index entry: a keyframe that has the word, with the word's weight in its BoW vector,
  /// so that a query gets every keyframe's L1 score from the index alone, with no vector merges.
  struct Posting {
    Slot slot;
    float weight;
  };
  std::vector<BowVector> bows_;                 // per slot
  std::vector<std::vector<Posting>> inverted_;  // per word
};

}  // namespace binloop
