#include "binloop/place/vlad_vocabulary.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <string>

#include "binloop/place/float_kmeans.h"
#include "binloop/place/model_file.h"
#include "binloop/util/hash_random.h"

namespace binloop {

namespace {
constexpr int kD = Desc256::kBits;
}

void expandBits(const Desc256& d, float* out) {
  for (int b = 0; b < kD; ++b) out[b] = static_cast<float>((d.w[b >> 6] >> (b & 63)) & 1u);
}

BinarySignature binarizeSigns(const std::vector<float>& v) {
  BinarySignature s((v.size() + 63) / 64, 0);
  for (size_t i = 0; i < v.size(); ++i)
    if (v[i] > 0) s[i >> 6] |= uint64_t{1} << (i & 63);
  return s;
}

std::vector<char> emptyWords(const std::vector<float>& v, int dims) {
  std::vector<char> empty;
  if (dims < 1) return empty;
  for (size_t first = 0; first + dims <= v.size(); first += dims) {
    empty.push_back(
        std::all_of(v.begin() + first, v.begin() + first + dims, [](float e) { return e == 0.f; }));
  }
  return empty;
}

BinarySignature binarizeSigns(const std::vector<float>& v, int dims, uint64_t empty_seed) {
  BinarySignature s = binarizeSigns(v);
  const std::vector<char> empty = emptyWords(v, dims);
  for (size_t w = 0; w < empty.size(); ++w) {
    if (!empty[w]) continue;
    HashRng coin(hashCombine(empty_seed, w));
    for (size_t i = w * dims; i < (w + 1) * dims; ++i)
      if (coin.next() & 1u) s[i >> 6] |= uint64_t{1} << (i & 63);
  }
  return s;
}

uint64_t descriptorSeed(const Descriptors& d) { return hashBytes(d.data(), d.size() * sizeof(Desc256)); }

void VladVocabulary::residual(const float* x, uint32_t node, float* out) const {
  const float* c = &centres_[static_cast<size_t>(node) * kD];
  float n2 = 0;
  for (int j = 0; j < kD; ++j) n2 += (x[j] - c[j]) * (x[j] - c[j]);
  const float inv = n2 > 0 ? 1.0f / std::sqrt(n2) : 0.0f;
  if (pca_t_.empty()) {
    for (int j = 0; j < kD; ++j) out[j] = (x[j] - c[j]) * inv;
    return;
  }
  // R((x - c) inv - m) = inv (R x - R c) - R m, and x is 0/1: R x is the sum of R's columns at x's set
  // bits, contiguous rows of the transposed rotation. About half the time of the plain product.
  const size_t base = static_cast<size_t>(node) * dims_;
  const float* rt = &pca_t_[base * kD];
  std::fill(out, out + dims_, 0.f);
  for (int j = 0; j < kD; ++j) {
    if (x[j] == 0.f) continue;
    const float* col = rt + static_cast<size_t>(j) * dims_;
    for (int i = 0; i < dims_; ++i) out[i] += col[i];
  }
  const float* rc = &pca_centre_[base];
  const float* rm = &pca_rot_mean_[base];
  for (int i = 0; i < dims_; ++i) out[i] = inv * (out[i] - rc[i]) - rm[i];
}

void VladVocabulary::quantizePca(const std::vector<float>& rotation) {
  const size_t rows = rotation.size() / kD;
  pca_q_.assign(rotation.size(), 0);
  pca_scale_.assign(rows, 0.f);
  for (size_t row = 0; row < rows; ++row) {
    const float* e = &rotation[row * kD];
    float top = 0;
    for (int j = 0; j < kD; ++j) top = std::max(top, std::fabs(e[j]));
    const float scale = top > 0 ? top / 127.f : 1.f;
    pca_scale_[row] = scale;
    for (int j = 0; j < kD; ++j) pca_q_[row * kD + j] = static_cast<int8_t>(std::lround(e[j] / scale));
  }
}

void VladVocabulary::preparePca() {
  pca_t_.clear(), pca_centre_.clear(), pca_rot_mean_.clear();
  if (pca_q_.empty()) return;
  const size_t nodes = centres_.size() / kD;
  pca_t_.assign(nodes * dims_ * kD, 0.f);
  pca_centre_.assign(nodes * dims_, 0.f);
  pca_rot_mean_.assign(nodes * dims_, 0.f);
  for (size_t node = 0; node < nodes; ++node) {
    for (int i = 0; i < dims_; ++i) {
      const size_t row = node * dims_ + i;
      const int8_t* q = &pca_q_[row * kD];
      double rc = 0, rm = 0;
      for (int j = 0; j < kD; ++j) {
        const float e = pca_scale_[row] * q[j];
        pca_t_[(node * kD + j) * dims_ + i] = e;
        rc += double(e) * centres_[node * kD + j];
        rm += double(e) * pca_mean_[node * kD + j];
      }
      pca_centre_[node * dims_ + i] = static_cast<float>(rc);
      pca_rot_mean_[node * dims_ + i] = static_cast<float>(rm);
    }
  }
}

std::vector<std::vector<float>> VladVocabulary::aggregate(const Descriptors& d) const {
  if (d.empty()) throw PlaceError("cannot build a VLAD signature from an empty descriptor set");
  std::vector<std::vector<float>> v(levels());
  for (int l = 0; l < levels(); ++l) v[l].assign(static_cast<size_t>(level_count_[l]) * dims_, 0.f);
  float x[kD], r[kD];
  for (const auto& desc : d) {
    expandBits(desc, x);
    uint32_t parent = 0;  // index into first_child_ (0 = root)
    for (int l = 0; l < levels() && child_count_[parent]; ++l) {
      const uint32_t first = first_child_[parent];
      const uint32_t node = first + nearestFloatCentre(x, &centres_[static_cast<size_t>(first) * kD],
                                                       static_cast<int>(child_count_[parent]), kD);
      residual(x, node, r);
      float* dst = &v[l][static_cast<size_t>(node - level_begin_[l]) * dims_];
      for (int j = 0; j < dims_; ++j) dst[j] += r[j];
      parent = node + 1;
    }
  }
  for (auto& lv : v) {
    double n2 = 0;
    for (float& e : lv) {
      e = std::copysign(std::pow(std::fabs(e), params_.alpha), e);
      n2 += double(e) * e;
    }
    if (n2 > 0)
      for (float& e : lv) e = static_cast<float>(e / std::sqrt(n2));
  }
  return v;
}

void VladVocabulary::trainPca(const std::vector<float>& data) {
  // LCS-PCA: per node, principal directions of its normalised residuals, scaled by 1/sqrt(eigenvalue).
  const size_t nodes = centres_.size() / kD;
  std::vector<std::vector<uint32_t>> members(nodes);
  for (size_t row = 0; row < data.size() / kD; ++row) {
    uint32_t parent = 0;
    for (int l = 0; l < params_.levels && child_count_[parent]; ++l) {
      const uint32_t first = first_child_[parent];
      const uint32_t node =
          first + nearestFloatCentre(&data[row * kD], &centres_[static_cast<size_t>(first) * kD],
                                     static_cast<int>(child_count_[parent]), kD);
      members[node].push_back(static_cast<uint32_t>(row));
      parent = node + 1;
    }
  }
  std::vector<float> rotation(nodes * params_.pca_dims * kD, 0.f);
  pca_mean_.assign(nodes * kD, 0.f);
  for (size_t node = 0; node < nodes; ++node) {
    Eigen::MatrixXd r(members[node].size(), kD);
    for (size_t i = 0; i < members[node].size(); ++i) {
      const float* x = &data[static_cast<size_t>(members[node][i]) * kD];
      const float* c = &centres_[node * kD];
      double n2 = 0;
      for (int j = 0; j < kD; ++j) n2 += (x[j] - c[j]) * (x[j] - c[j]);
      const double inv = n2 > 0 ? 1.0 / std::sqrt(n2) : 0.0;
      for (int j = 0; j < kD; ++j) r(i, j) = (x[j] - c[j]) * inv;
    }
    const Eigen::RowVectorXd mean = r.colwise().mean();
    r.rowwise() -= mean;
    const Eigen::MatrixXd cov = r.transpose() * r / std::max<double>(1, r.rows() - 1);
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(cov);
    for (int i = 0; i < params_.pca_dims; ++i) {
      const int col = kD - 1 - i;  // eigenvalues ascend
      const double scale = 1.0 / std::sqrt(std::max(es.eigenvalues()(col), 1e-6));
      for (int j = 0; j < kD; ++j) {
        rotation[(node * params_.pca_dims + i) * kD + j] =
            static_cast<float>(es.eigenvectors()(j, col) * scale);
      }
    }
    for (int j = 0; j < kD; ++j) pca_mean_[node * kD + j] = static_cast<float>(mean(j));
  }
  quantizePca(rotation);
}

VladVocabulary VladVocabulary::train(const std::vector<Descriptors>& images, const VladParams& p,
                                     const ProgressFn& progress) {
  if (p.k < 1 || p.levels < 1) throw PlaceError("VLAD vocabulary needs k >= 1 and levels >= 1");
  if (p.pca_dims < 0 || p.pca_dims > kD) throw PlaceError("--pca must be between 0 and 256");
  size_t total = 0;
  for (const auto& im : images) total += im.size();
  const size_t min_needed = static_cast<size_t>(std::pow(p.k, p.levels)) * 20;
  if (total < min_needed) {
    throw PlaceError("too few descriptors to train a VLAD vocabulary of " + std::to_string(p.k) + "^" +
                     std::to_string(p.levels) + " words: " + std::to_string(total) + " (need " +
                     std::to_string(min_needed) + ")");
  }
  // Even sampling keeps every image represented and the result independent of thread timing.
  const size_t stride =
      std::max<size_t>(1, (total + p.max_training_descriptors - 1) / p.max_training_descriptors);
  std::vector<float> data;
  size_t seen = 0;
  for (const auto& im : images) {
    for (const auto& d : im) {
      if (seen++ % stride == 0) {
        data.resize(data.size() + kD);
        expandBits(d, &data[data.size() - kD]);
      }
    }
  }
  VladVocabulary v;
  v.params_ = p;
  v.first_child_.push_back(0);
  v.child_count_.push_back(0);
  struct Pending {
    uint32_t slot;  // index into first_child_ of the node to split
    std::vector<uint32_t> rows;
  };
  std::vector<Pending> level{{0, {}}};
  level[0].rows.resize(data.size() / kD);
  for (size_t i = 0; i < level[0].rows.size(); ++i) level[0].rows[i] = static_cast<uint32_t>(i);
  for (int l = 0; l < p.levels; ++l) {
    std::vector<Pending> next;
    v.level_begin_.push_back(static_cast<uint32_t>(v.centres_.size() / kD));
    for (auto& pend : level) {
      std::vector<float> sub;
      sub.reserve(pend.rows.size() * kD);
      for (uint32_t r : pend.rows)
        sub.insert(sub.end(), &data[static_cast<size_t>(r) * kD], &data[static_cast<size_t>(r) * kD] + kD);
      FloatKMeansResult km =
          floatKMeans(sub, kD, p.k, hashCombine(p.seed, pend.slot * 131 + l), p.max_iterations);
      if (km.k < p.k) {
        throw PlaceError("degenerate VLAD vocabulary: a node at level " + std::to_string(l + 1) +
                         " split into " + std::to_string(km.k) + " clusters instead of " +
                         std::to_string(p.k) + " (" + std::to_string(km.dropped_empty) +
                         " empty); use more or more varied training images");
      }
      const auto first = static_cast<uint32_t>(v.centres_.size() / kD);
      v.first_child_[pend.slot] = first;
      v.child_count_[pend.slot] = static_cast<uint32_t>(km.k);
      v.centres_.insert(v.centres_.end(), km.centres.begin(), km.centres.end());
      std::vector<Pending> kids(km.k);
      for (int c = 0; c < km.k; ++c) {
        kids[c].slot = first + c + 1;
        v.first_child_.push_back(0);
        v.child_count_.push_back(0);
      }
      for (size_t i = 0; i < pend.rows.size(); ++i) kids[km.assignment[i]].rows.push_back(pend.rows[i]);
      for (auto& kd : kids) next.push_back(std::move(kd));
    }
    v.level_count_.push_back(static_cast<uint32_t>(v.centres_.size() / kD) - v.level_begin_.back());
    if (progress) progress(l + 1, p.levels + (p.pca_dims > 0));
    level = std::move(next);
  }
  if (p.pca_dims > 0) {
    v.trainPca(data);
    v.dims_ = p.pca_dims;
    v.preparePca();
    if (progress) progress(p.levels + 1, p.levels + 1);
  }
  return v;
}

void VladVocabulary::write(ModelWriter& w) const {
  // The fifth value says the rotation is stored in 8 bits (files with four values hold it as floats).
  const std::vector<float> par{params_.alpha, static_cast<float>(params_.pca_dims),
                               static_cast<float>(params_.k), static_cast<float>(params_.levels), 1.f};
  w.section("VPAR", par);
  w.section("VCEN", centres_);
  w.section("VFCH", first_child_);
  w.section("VNCH", child_count_);
  w.section("VLVB", level_begin_);
  w.section("VLVC", level_count_);
  w.section("VPCA", pca_q_);
  w.section("VPCS", pca_scale_);
  w.section("VPCM", pca_mean_);
}

VladVocabulary VladVocabulary::read(ModelReader& r) {
  VladVocabulary v;
  const auto par = r.section<float>("VPAR");
  if (par.size() != 4 && !(par.size() == 5 && par[4] == 1.f)) {
    throw PlaceError(r.path() + ": VLAD parameter section has " + std::to_string(par.size()) +
                     " values, expected 4, or 5 with the last 1");
  }
  v.params_.alpha = par[0];
  v.params_.pca_dims = static_cast<int>(par[1]);
  v.params_.k = static_cast<int>(par[2]);
  v.params_.levels = static_cast<int>(par[3]);
  v.centres_ = r.section<float>("VCEN");
  v.first_child_ = r.section<uint32_t>("VFCH");
  v.child_count_ = r.section<uint32_t>("VNCH");
  v.level_begin_ = r.section<uint32_t>("VLVB");
  v.level_count_ = r.section<uint32_t>("VLVC");
  const size_t nodes = v.centres_.size() / kD;
  v.dims_ = v.params_.pca_dims > 0 ? v.params_.pca_dims : kD;
  if (par.size() == 5) {
    v.pca_q_ = r.section<int8_t>("VPCA");
    v.pca_scale_ = r.section<float>("VPCS");
  } else {
    v.quantizePca(r.section<float>("VPCA"));
  }
  v.pca_mean_ = r.section<float>("VPCM");
  bool ok =
      v.centres_.size() == nodes * kD && nodes > 0 && v.first_child_.size() == nodes + 1 &&
      v.child_count_.size() == nodes + 1 && !v.level_begin_.empty() &&
      v.level_begin_.size() == v.level_count_.size() && v.params_.pca_dims >= 0 && v.params_.pca_dims <= kD &&
      (v.params_.pca_dims > 0) == !v.pca_q_.empty() &&
      (v.pca_q_.empty() || (v.pca_q_.size() == nodes * v.dims_ * kD &&
                            v.pca_scale_.size() == nodes * v.dims_ && v.pca_mean_.size() == nodes * kD));
  for (size_t i = 0; ok && i <= nodes; ++i)
    ok = v.child_count_[i] == 0 || v.first_child_[i] + v.child_count_[i] <= nodes;
  if (!ok) throw PlaceError(r.path() + ": VLAD vocabulary sections are inconsistent");
  v.preparePca();
  return v;
}

}  // namespace binloop
