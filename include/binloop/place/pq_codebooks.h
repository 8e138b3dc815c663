#pragma once
// Product quantization of VLAD signatures (thesis 4.3): the residual v_i of word i is quantized by its own
// codebook Q_i of m centroids (eq. 4.11-4.13); an image becomes an index vector of one code per word.
// Distances: SDC compares two code vectors through per-word centroid tables (4.14); ADC compares a raw
// VLAD with a code vector (4.15). Both are sums of squared distances.
#include <cstdint>
#include <vector>

#include "binloop/place/model_file.h"

namespace binloop {

using PqCodes = std::vector<uint16_t>;  // one code per word

class PqCodebooks {
 public:
  /// `vlads`: training VLADs, each words × dims floats. Throws PlaceError when a word has fewer
  /// distinct residuals than m (too few training images).
  static PqCodebooks train(const std::vector<std::vector<float>>& vlads, int words, int dims, int m,
                           uint64_t seed);

  PqCodes encode(const std::vector<float>& vlad) const;
  float sdc(const PqCodes& a, const PqCodes& b) const;
  float adc(const std::vector<float>& vlad, const PqCodes& b) const;

  int words() const { return words_; }
  int dims() const { return dims_; }
  int m() const { return m_; }
  const float* centroid(int word, int code) const {
    return &codebooks_[(static_cast<size_t>(word) * m_ + code) * dims_];
  }

  void write(ModelWriter& w) const;
  static PqCodebooks read(ModelReader& r);

 private:
  int words_ = 0, dims_ = 0, m_ = 0;
  std::vector<float> codebooks_;  // words × m × dims
  std::vector<float> scales_;     // per word: the 16-bit step the file stores the codebooks in
  std::vector<float> sdc_table_;  // words × m × m squared distances
  void buildTable();
};

}  // namespace binloop
