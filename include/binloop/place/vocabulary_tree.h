#pragma once
// The hierarchical vocabulary of `hbow` (DBoW2's design, our code): a tree of k-majority centres with
// `levels` levels below the root, whose leaves are the words; words carry an IDF weight; an image is
// turned into an L1-normalised BowVector by walking each descriptor down the tree.
//
// Nodes are stored breadth first with each node's children contiguous, so a level of the descent is a
// scan over k adjacent descriptors. The node arrays are views: into vectors the tree owns (trained or
// imported), or straight into a mapped model file, so that loading a 1M-word tree copies nothing.
// Copies of a tree share those arrays (they are never modified).
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "binloop/place/bow_vector.h"
#include "binloop/place/model_file.h"
#include "binloop/types/binary_descriptor.h"
#include "binloop/util/progress_bar.h"

namespace binloop {

struct VocabTreeParams {
  int k = 10;
  int levels = 6;
  Weighting weighting = Weighting::kTfIdf;
  uint64_t seed = 1;
  int max_iterations = 10;
};

class VocabularyTree {
 public:
  /// One Descriptors per training image (images give the IDF). Throws PlaceError when there are too
  /// few descriptors for the requested k.
  static VocabularyTree train(const std::vector<Descriptors>& images, const VocabTreeParams& p,
                              const ProgressFn& progress = {});

  /// Builds from a node list in any order (e.g. an imported DBoW2 file): node 0 is the root; every other
  /// node names its parent; leaves carry their word weight. Throws PlaceError on an inconsistent tree.
  struct InputNode {
    uint32_t parent;
    Desc256 descriptor;
    bool is_leaf;
    float weight;
  };
  static VocabularyTree fromNodes(int k, int levels, Weighting w, const std::vector<InputNode>& nodes);

  /// Word of one descriptor; `path_node` (optional) receives nodeOf(d, node_depth).
  uint32_t wordOf(const Desc256& d, int node_depth = 0, uint32_t* path_node = nullptr) const;
  /// The node `depth` levels below `from` (the root by default) that a descriptor passes (a shallower leaf
  /// stands for itself): with k = 10, depth 2 cuts descriptor space into ~100 cells, ORB-SLAM2's cells for
  /// matching by words.
  uint32_t nodeOf(const Desc256& d, int depth, uint32_t from = 0) const;
  /// BoW vector of an image (L1-normalised, weighted by the vocabulary's weighting), and optionally the
  /// direct index at `fv_depth` levels below the root.
  void transform(const Descriptors& d, BowVector* bow, FeatureVector* fv = nullptr, int fv_depth = 2) const;

  size_t words() const { return word_node_.size(); }
  size_t nodes() const { return desc_.size; }
  int k() const { return k_; }
  int levels() const { return levels_; }
  Weighting weighting() const { return weighting_; }
  float weight(uint32_t word) const { return weight_[word]; }
  const Desc256& wordDescriptor(uint32_t word) const { return desc_[word_node_[word]]; }

  void write(ModelWriter& w) const;
  static VocabularyTree read(ModelReader& r);

 private:
  int k_ = 0, levels_ = 0;
  Weighting weighting_ = Weighting::kTfIdf;
  struct Owned;                          // the arrays of a tree built in memory
  std::shared_ptr<const void> storage_;  // what the views below point into
  SectionView<Desc256> desc_;            // per node (root's is unused)
  SectionView<uint32_t> first_child_;    // per node
  SectionView<uint32_t> child_count_;    // per node, 0 for leaves
  SectionView<float> weight_;            // per word
  std::vector<uint32_t> node_word_;      // per node, UINT32_MAX for inner nodes
  std::vector<uint32_t> word_node_;      // per word
  /// Takes the arrays of a tree built in memory (train, fromNodes) and indexes its words.
  void adopt(std::shared_ptr<Owned> owned);
  void indexWords();
  /// Words (and nodes at `fv_depth`, when fv_node is given) of n descriptors, descended together.
  void descend(const Desc256* d, size_t n, int fv_depth, uint32_t* word, uint32_t* fv_node) const;
  std::vector<float> computeIdf(const std::vector<Descriptors>& images) const;
};

}  // namespace binloop
