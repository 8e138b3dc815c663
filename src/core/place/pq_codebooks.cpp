#include "binloop/place/pq_codebooks.h"

#include <string>

#include "binloop/place/float_kmeans.h"
#include "binloop/util/hash_random.h"

namespace binloop {

PqCodebooks PqCodebooks::train(const std::vector<std::vector<float>>& vlads, int words, int dims, int m, uint64_t seed) {
  if (m < 1 || m > 65535) throw PlaceError("PQ codebook size must be 1..65535, got " + std::to_string(m));
  PqCodebooks pq;
  pq.words_ = words;
  pq.dims_ = dims;
  pq.m_ = m;
  for (int w = 0; w < words; ++w) {
    std::vector<float> sub;
    for (const auto& v : vlads) {
      if (v.size() != static_cast<size_t>(words) * dims) throw PlaceError("PQ training VLAD of the wrong size");
      sub.insert(sub.end(), &v[static_cast<size_t>(w) * dims], &v[static_cast<size_t>(w) * dims] + dims);
    }
    FloatKMeansResult km = floatKMeans(sub, dims, m, hashCombine(seed, w), 25);
    if (km.k < m)
      throw PlaceError("degenerate PQ codebook for word " + std::to_string(w) + ": " + std::to_string(km.k) +
                       " distinct centroids of " + std::to_string(m) + " from " + std::to_string(vlads.size()) +
                       " training images (train on more images or lower --pq-codes)");
    pq.codebooks_.insert(pq.codebooks_.end(), km.centres.begin(), km.centres.end());
  }
  pq.buildTable();
  return pq;
}

void PqCodebooks::buildTable() {
  sdc_table_.resize(static_cast<size_t>(words_) * m_ * m_);
  for (int w = 0; w < words_; ++w)
    for (int a = 0; a < m_; ++a)
      for (int b = 0; b < m_; ++b)
        sdc_table_[(static_cast<size_t>(w) * m_ + a) * m_ + b] = squaredDistance(centroid(w, a), centroid(w, b), dims_);
}

PqCodes PqCodebooks::encode(const std::vector<float>& vlad) const {
  PqCodes c(words_);
  for (int w = 0; w < words_; ++w)
    c[w] = static_cast<uint16_t>(nearestFloatCentre(&vlad[static_cast<size_t>(w) * dims_], centroid(w, 0), m_, dims_));
  return c;
}

float PqCodebooks::sdc(const PqCodes& a, const PqCodes& b) const {
  float s = 0;
  for (int w = 0; w < words_; ++w) s += sdc_table_[(static_cast<size_t>(w) * m_ + a[w]) * m_ + b[w]];
  return s;
}

float PqCodebooks::adc(const std::vector<float>& vlad, const PqCodes& b) const {
  float s = 0;
  for (int w = 0; w < words_; ++w) s += squaredDistance(&vlad[static_cast<size_t>(w) * dims_], centroid(w, b[w]), dims_);
  return s;
}

void PqCodebooks::write(ModelWriter& w) const {
  w.section("QPAR", std::vector<uint32_t>{static_cast<uint32_t>(words_), static_cast<uint32_t>(dims_), static_cast<uint32_t>(m_)});
  w.section("QCBK", codebooks_);
}

PqCodebooks PqCodebooks::read(ModelReader& r) {
  PqCodebooks pq;
  const auto par = r.section<uint32_t>("QPAR");
  if (par.size() != 3) throw PlaceError(r.path() + ": PQ parameter section malformed");
  pq.words_ = static_cast<int>(par[0]);
  pq.dims_ = static_cast<int>(par[1]);
  pq.m_ = static_cast<int>(par[2]);
  pq.codebooks_ = r.section<float>("QCBK");
  if (pq.m_ < 1 || pq.codebooks_.size() != static_cast<size_t>(pq.words_) * pq.m_ * pq.dims_)
    throw PlaceError(r.path() + ": PQ codebooks hold " + std::to_string(pq.codebooks_.size()) + " floats, expected " +
                     std::to_string(static_cast<size_t>(pq.words_) * pq.m_ * pq.dims_));
  pq.buildTable();
  return pq;
}

}  // namespace binloop
