#pragma once
// Tracking's index of its keyframes by appearance, for relocalisation (ORB-SLAM2's KeyFrameDatabase and
// DetectRelocalizationCandidates): a bag-of-words vector per keyframe from the hbow vocabulary and an
// inverted file from word to keyframes. A lost frame asks which keyframes look like it, anywhere in the
// map, instead of trying only the most recent ones. It belongs to the tracking stage and holds only what
// tracking made (its own keyframes' descriptors), so no other stage's state is shared.
#include <functional>
#include <memory>
#include <unordered_map>
#include <vector>

#include "binloop/map/ids.h"
#include "binloop/place/bow_vector.h"
#include "binloop/place/vocabulary_tree.h"

namespace binloop {

class StateWriter;
class StateReader;

class KeyframeDatabase {
 public:
  explicit KeyframeDatabase(std::shared_ptr<const VocabularyTree> voc);

  void add(SlamKeyframeId id, const Descriptors& d);
  /// A keyframe local mapping culled: never a candidate again.
  void remove(SlamKeyframeId id);
  size_t size() const { return bows_.size(); }
  /// The bag-of-words vectors (in id order); load() replaces them and rebuilds the inverted file. Only
  /// meaningful with the vocabulary that made them: the tracker checks its identity. A database made without
  /// a vocabulary (null) can load, to read past an index it will not use.
  void save(StateWriter& w) const;
  void load(StateReader& r);

  /// Keyframes that look like `d`, best first, at most `max`: those sharing at least 80 % of the largest
  /// number of words any keyframe shares with it are scored (L1); each one's score is summed with its
  /// covisible neighbours' (`neighbours`, strongest first) so that a place seen by several keyframes beats
  /// a single look-alike; groups above 75 % of the best sum give their best-scoring keyframe.
  using NeighboursFn = std::function<std::vector<SlamKeyframeId>(SlamKeyframeId)>;
  std::vector<SlamKeyframeId> candidates(const Descriptors& d, size_t max,
                                         const NeighboursFn& neighbours) const;

 private:
  std::shared_ptr<const VocabularyTree> voc_;
  std::unordered_map<SlamKeyframeId, BowVector> bows_;
  std::unordered_map<uint32_t, std::vector<SlamKeyframeId>> inverted_;
};

}  // namespace binloop
