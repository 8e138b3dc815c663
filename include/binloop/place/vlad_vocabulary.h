#pragma once
// The vocabulary of the VLAD family: float centres in the binary-expanded descriptor space (each of the
// 256 bits a 0/1 dimension), arranged as a tree of `levels` levels with `k` children per node. One level
// (`levels` = 1) is plain VLAD's flat vocabulary of k words; HMVLAD uses every level, one VLAD each
// (thesis eq. 4.8). Optional LCS-PCA with whitening per node (eq. 4.6).
//
// aggregate() gives, per level, v_i = sum over descriptors x assigned to word i of (x - c_i)/|x - c_i|
// (eq. 4.2), then |v|^alpha sign(v) (4.3) and L2 normalisation of the level's vector (4.4).
#include <cstdint>
#include <vector>

#include "binloop/place/model_file.h"
#include "binloop/place/vocabulary_tree.h"
#include "binloop/types/binary_descriptor.h"

namespace binloop {

struct VladParams {
  int k = 4;  // thesis: VLAD 4 words; HMVLAD k = 2 with 2 levels (2 and 4 nodes)
  int levels = 1;
  float alpha = 0.5f;  // power normalisation exponent
  int pca_dims = 0;    // 0: no LCS-PCA; otherwise dimensions kept per word (whitened)
  uint64_t seed = 1;
  int max_iterations = 25;
  size_t max_training_descriptors = 200000;  // sampled evenly from all training descriptors
};

/// Bits of sign(v) > 0, packed in 64-bit words.
using BinarySignature = std::vector<uint64_t>;
BinarySignature binarizeSigns(const std::vector<float>& v);
/// For a VLAD of words of `dims` floats: 1 for each word no descriptor fell into (its residual all zero).
std::vector<char> emptyWords(const std::vector<float>& v, int dims);
/// The same, for a VLAD of words of `dims` floats, except that a word no descriptor fell into gets coin-flip
/// bits seeded by `empty_seed` and the word's index. Why: its all-zero residual would give all-zero bits,
/// and two images with few features (a blank wall, a blurred sky) would agree on every empty word and
/// match each other more closely than true revisits do (real_heldout, 64 words: two such pairs outranked
/// every true loop). Coin flips make an empty word look unrelated to anything, which is what it knows.
BinarySignature binarizeSigns(const std::vector<float>& v, int dims, uint64_t empty_seed);
/// A seed for binarizeSigns from the image's own descriptors: the same image, the same bits.
uint64_t descriptorSeed(const Descriptors& d);
inline int hammingBits(const BinarySignature& a, const BinarySignature& b) {
  int d = 0;
  for (size_t i = 0; i < a.size(); ++i) d += __builtin_popcountll(a[i] ^ b[i]);
  return d;
}

class VladVocabulary {
 public:
  static VladVocabulary train(const std::vector<Descriptors>& images, const VladParams& p,
                              const ProgressFn& progress = {});

  int levels() const { return static_cast<int>(level_begin_.size()); }
  int wordsAtLevel(int level) const { return static_cast<int>(level_count_[level - 1]); }  // level from 1
  int dims() const { return dims_; }  // per word: 256, or pca_dims
  /// One normalised VLAD per level (index 0 = level 1), each wordsAtLevel × dims floats.
  /// Throws PlaceError on an empty descriptor set.
  std::vector<std::vector<float>> aggregate(const Descriptors& d) const;

  void write(ModelWriter& w) const;
  static VladVocabulary read(ModelReader& r);
  const VladParams& params() const { return params_; }

 private:
  /// LCS-PCA for every node of the trained tree from the training rows `data` (kD floats each).
  void trainPca(const std::vector<float>& data);
  VladParams params_;
  int dims_ = Desc256::kBits;
  std::vector<float> centres_;                       // node × 256 (nodes breadth first, root excluded)
  std::vector<uint32_t> first_child_, child_count_;  // per node + 1 (entry 0 = root)
  std::vector<uint32_t> level_begin_, level_count_;  // node ranges per level
  // Per node: the whitened rotation (dims × 256) as 8-bit integers with one scale per row, and the 256-float
  // mean. Why 8 bits: float rotations of 128 dimensions made a 64-word model 8.5 MB, 8 bits 2.1 MB; the
  // quantisation error (at most half a step of 1/127 of a row's largest entry) moved no loop-set result
  // (docs/decisions.md, "LCS-PCA shipped in 96 and 64 dimensions").
  std::vector<int8_t> pca_q_;
  std::vector<float> pca_scale_, pca_mean_;
  // Derived from the three above by preparePca(), for residual(): per node the rotation transposed (256 ×
  // dims, so that a set bit adds one contiguous row), the rotated centre and the rotated mean.
  std::vector<float> pca_t_, pca_centre_, pca_rot_mean_;
  /// Keeps `rotation` (nodes × dims × 256 floats) as pca_q_ and pca_scale_.
  void quantizePca(const std::vector<float>& rotation);
  void preparePca();
  void residual(const float* x, uint32_t node, float* out) const;
};

/// Expands a descriptor to 256 floats of 0/1 (the thesis' "binary expansion").
void expandBits(const Desc256& d, float* out);

}  // namespace binloop
