#pragma once
// Training of every model type into a model file (what `binloop train` runs). Sizes not given take the
// thesis defaults of each model.
#include <string>
#include <vector>

#include "binloop/place/model_file.h"
#include "binloop/place/vocabulary_tree.h"
#include "binloop/types/binary_descriptor.h"

namespace binloop {

struct TrainOptions {
  int k = 0;          // 0: model default (hbow 10, vlad 4, hmvlad 2, vladpq 4)
  int levels = 0;     // 0: model default (hbow 6, hmvlad 2, vlad/vladpq 1)
  int words = 10000;  // fabmap flat vocabulary
  int pq_codes = 32;
  int pca_dims = 0;
  float alpha = 0.5f;
  uint64_t seed = 1;
  size_t max_descriptors = 200000;  // sample for the flat and VLAD vocabularies
  size_t fabmap_samples = 200;      // training places kept for sampled evidence
  /// Recorded in the header: the extractor that made `images` (unknown when not said).
  ExtractorSettings extractor{};
};

/// Trains `type` on `images` (one descriptor set per image) and writes `out`. Returns the header written.
/// Throws PlaceError for degenerate data (too few descriptors, empty clusters).
ModelHeader trainModel(ModelType type, const std::vector<Descriptors>& images, const TrainOptions& o,
                       const std::string& out, const ProgressFn& progress = {});

/// Writes a vocabulary tree (trained or imported) as an `hbow` model file.
void saveHbowModel(const VocabularyTree& t, ModelHeader h, const std::string& out);

/// Fingerprint of the training data (order-sensitive), stored in every model header.
uint64_t trainingHash(const std::vector<Descriptors>& images);

}  // namespace binloop
