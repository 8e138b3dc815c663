#include "binloop/place/pq_codebooks.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "binloop/place/float_kmeans.h"
#include "binloop/util/hash_random.h"

namespace binloop {

namespace {

// The codebooks are written as int16 steps of one scale per word: half the bytes of floats (the shipped
// 64-word, 32-code vladpq fits in a tracked file) at a relative error of 1/32767 of the word's largest value.
constexpr uint32_t kFixed16 = 1;

std::vector<float> fixedPointScales(const std::vector<float>& values, int words, size_t per_word) {
  std::vector<float> scales(words, 1.f);
  for (int w = 0; w < words; ++w) {
    float mx = 0;
    for (size_t i = 0; i < per_word; ++i) mx = std::max(mx, std::fabs(values[w * per_word + i]));
    if (mx > 0) scales[w] = mx / 32767.f;
  }
  return scales;
}

int16_t toFixed(float v, float scale) {
  return static_cast<int16_t>(std::clamp(std::lround(v / scale), -32767L, 32767L));
}

}  // namespace

PqCodebooks PqCodebooks::train(const std::vector<std::vector<float>>& vlads, int words, int dims, int m,
                               uint64_t seed) {
  if (m < 1 || m > 65535) throw PlaceError("PQ codebook size must be 1..65535, got " + std::to_string(m));
  PqCodebooks pq;
  pq.words_ = words;
  pq.dims_ = dims;
  pq.m_ = m;
  for (int w = 0; w < words; ++w) {
    std::vector<float> sub;
    for (const auto& v : vlads) {
      if (v.size() != static_cast<size_t>(words) * dims)
        throw PlaceError("PQ training VLAD of the wrong size");
      sub.insert(sub.end(), &v[static_cast<size_t>(w) * dims], &v[static_cast<size_t>(w) * dims] + dims);
    }
    FloatKMeansResult km = floatKMeans(sub, dims, m, hashCombine(seed, w), 25);
    if (km.k < m) {
      throw PlaceError("degenerate PQ codebook for word " + std::to_string(w) + ": " + std::to_string(km.k) +
                       " distinct centroids of " + std::to_string(m) + " from " +
                       std::to_string(vlads.size()) +
                       " training images (train on more images or lower --pq-codes)");
    }
    pq.codebooks_.insert(pq.codebooks_.end(), km.centres.begin(), km.centres.end());
  }
  // Stored as 16-bit steps (below): round now so that a trained model and the same model loaded from its
  // file give the same codes and distances.
  pq.scales_ = fixedPointScales(pq.codebooks_, words, static_cast<size_t>(m) * dims);
  for (size_t i = 0; i < pq.codebooks_.size(); ++i) {
    const float s = pq.scales_[i / (static_cast<size_t>(m) * dims)];
    pq.codebooks_[i] = static_cast<float>(toFixed(pq.codebooks_[i], s)) * s;
  }
  pq.buildTable();
  return pq;
}

void PqCodebooks::buildTable() {
  sdc_table_.resize(static_cast<size_t>(words_) * m_ * m_);
  for (int w = 0; w < words_; ++w) {
    for (int a = 0; a < m_; ++a) {
      for (int b = 0; b < m_; ++b) {
        sdc_table_[(static_cast<size_t>(w) * m_ + a) * m_ + b] =
            squaredDistance(centroid(w, a), centroid(w, b), dims_);
      }
    }
  }
}

PqCodes PqCodebooks::encode(const std::vector<float>& vlad) const {
  PqCodes c(words_);
  for (int w = 0; w < words_; ++w) {
    c[w] = static_cast<uint16_t>(
        nearestFloatCentre(&vlad[static_cast<size_t>(w) * dims_], centroid(w, 0), m_, dims_));
  }
  return c;
}

float PqCodebooks::sdc(const PqCodes& a, const PqCodes& b) const {
  float s = 0;
  for (int w = 0; w < words_; ++w) s += sdc_table_[(static_cast<size_t>(w) * m_ + a[w]) * m_ + b[w]];
  return s;
}

float PqCodebooks::adc(const std::vector<float>& vlad, const PqCodes& b) const {
  float s = 0;
  for (int w = 0; w < words_; ++w)
    s += squaredDistance(&vlad[static_cast<size_t>(w) * dims_], centroid(w, b[w]), dims_);
  return s;
}

void PqCodebooks::write(ModelWriter& w) const {
  w.section("QPAR", std::vector<uint32_t>{static_cast<uint32_t>(words_), static_cast<uint32_t>(dims_),
                                          static_cast<uint32_t>(m_), kFixed16});
  std::vector<int16_t> steps(codebooks_.size());
  for (size_t i = 0; i < steps.size(); ++i)
    steps[i] = toFixed(codebooks_[i], scales_[i / (static_cast<size_t>(m_) * dims_)]);
  w.section("QSCL", scales_);
  w.section("QC16", steps);
}

PqCodebooks PqCodebooks::read(ModelReader& r) {
  PqCodebooks pq;
  const auto par = r.section<uint32_t>("QPAR");
  // Three parameters: a file from before the 16-bit codebooks, which holds floats.
  if (par.size() != 3 && !(par.size() == 4 && par[3] == kFixed16))
    throw PlaceError(r.path() + ": PQ parameter section malformed");
  pq.words_ = static_cast<int>(par[0]);
  pq.dims_ = static_cast<int>(par[1]);
  pq.m_ = static_cast<int>(par[2]);
  if (par.size() == 3) {
    pq.codebooks_ = r.section<float>("QCBK");
  } else {
    pq.scales_ = r.section<float>("QSCL");
    const std::vector<int16_t> steps = r.section<int16_t>("QC16");
    const size_t per_word = static_cast<size_t>(pq.m_) * pq.dims_;
    if (pq.scales_.size() != static_cast<size_t>(pq.words_) || steps.size() != per_word * pq.words_) {
      throw PlaceError(r.path() + ": PQ codebooks hold " + std::to_string(steps.size()) + " values and " +
                       std::to_string(pq.scales_.size()) + " scales, expected " +
                       std::to_string(per_word * pq.words_) + " and " + std::to_string(pq.words_));
    }
    pq.codebooks_.resize(steps.size());
    for (size_t i = 0; i < steps.size(); ++i)
      pq.codebooks_[i] = static_cast<float>(steps[i]) * pq.scales_[i / per_word];
  }
  if (pq.m_ < 1 || pq.codebooks_.size() != static_cast<size_t>(pq.words_) * pq.m_ * pq.dims_) {
    throw PlaceError(r.path() + ": PQ codebooks hold " + std::to_string(pq.codebooks_.size()) +
                     " floats, expected " +
                     std::to_string(static_cast<size_t>(pq.words_) * pq.m_ * pq.dims_));
  }
  if (pq.scales_.empty())
    pq.scales_ = fixedPointScales(pq.codebooks_, pq.words_, static_cast<size_t>(pq.m_) * pq.dims_);
  pq.buildTable();
  return pq;
}

}  // namespace binloop
