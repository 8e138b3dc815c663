#pragma once
// The flat binary vocabulary of `fabmap` (thesis 3.4.2: 10 000 words by binary k-means; here k-majority,
// the binary form of the same clustering). Images become word-presence sets by brute-force nearest word.
#include <cstdint>
#include <vector>

#include "binloop/place/model_file.h"
#include "binloop/place/vocabulary_tree.h"
#include "binloop/types/binary_descriptor.h"

namespace binloop {

struct FlatVocabParams {
  int words = 10000;
  uint64_t seed = 1;
  int max_iterations = 8;
  size_t max_training_descriptors = 200000;
};

class FlatVocabulary {
 public:
  static FlatVocabulary train(const std::vector<Descriptors>& images, const FlatVocabParams& p,
                              const ProgressFn& progress = {});
  explicit FlatVocabulary(std::vector<Desc256> words = {}) : words_(std::move(words)) {}
  /// Sorted ids of the words present in the image.
  std::vector<uint32_t> presence(const Descriptors& d) const;
  size_t size() const { return words_.size(); }
  const std::vector<Desc256>& words() const { return words_; }

 private:
  std::vector<Desc256> words_;
};

}  // namespace binloop
