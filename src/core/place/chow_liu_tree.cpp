#include "binloop/place/chow_liu_tree.h"

#include <cmath>
#include <limits>
#include <string>

#include "binloop/place/place_error.h"

namespace binloop {

double ChowLiuTree::mutualInformation(double n, double na, double nb, double nab) {
  // Joint counts of the four states from the marginal and pair counts.
  const double c[4] = {n - na - nb + nab, nb - nab, na - nab, nab};  // (a,b) = 00, 01, 10, 11
  const double pa[2] = {(n - na) / n, na / n}, pb[2] = {(n - nb) / n, nb / n};
  double mi = 0;
  for (int s = 0; s < 4; ++s) {
    const double p = c[s] / n;
    if (p > 0) mi += p * std::log(p / (pa[s >> 1] * pb[s & 1]));
  }
  return mi;
}

ChowLiuTree ChowLiuTree::learn(const std::vector<std::vector<uint32_t>>& images, uint32_t words,
                               double pseudo, const ProgressFn& progress) {
  if (images.size() < 2)
    throw PlaceError("Chow-Liu tree needs at least 2 training images, got " + std::to_string(images.size()));
  if (words < 2) throw PlaceError("Chow-Liu tree needs at least 2 words");
  const double n = static_cast<double>(images.size()) + 4 * pseudo;
  std::vector<double> count(words, 0);
  // Pair counts in a packed upper triangle: entry (a, b), a < b, at a*words - a*(a+1)/2 + (b - a - 1).
  std::vector<uint32_t> pair(static_cast<size_t>(words) * (words - 1) / 2, 0);
  auto at = [words](size_t a, size_t b) { return a * words - a * (a + 1) / 2 + (b - a - 1); };
  for (size_t im = 0; im < images.size(); ++im) {
    const auto& w = images[im];
    for (size_t i = 0; i < w.size(); ++i) {
      if (w[i] >= words) {
        throw PlaceError("training image names word " + std::to_string(w[i]) + " of " +
                         std::to_string(words));
      }
      count[w[i]]++;
      for (size_t j = i + 1; j < w.size(); ++j) pair[at(w[i], w[j])]++;
    }
    if (progress && im % 64 == 0) progress(im, images.size() * 2);
  }
  // Smoothed counts: each of the four joint states of a pair gets `pseudo`.
  auto na = [&](uint32_t a) { return count[a] + 2 * pseudo; };
  auto nab = [&](uint32_t a, uint32_t b) { return (a < b ? pair[at(a, b)] : pair[at(b, a)]) + pseudo; };

  // Prim's algorithm for the maximum spanning tree on the dense MI graph.
  ChowLiuTree t;
  t.parent_.assign(words, 0);
  std::vector<double> best(words, -std::numeric_limits<double>::infinity());
  std::vector<char> in_tree(words, 0);
  t.root_ = 0;
  in_tree[0] = 1;
  for (uint32_t v = 1; v < words; ++v)
    best[v] = mutualInformation(n, na(0), na(v), nab(0, v)), t.parent_[v] = 0;
  for (uint32_t added = 1; added < words; ++added) {
    uint32_t u = 0;
    double bu = -std::numeric_limits<double>::infinity();
    for (uint32_t v = 0; v < words; ++v)
      if (!in_tree[v] && best[v] > bu) bu = best[v], u = v;
    in_tree[u] = 1;
    for (uint32_t v = 0; v < words; ++v) {
      if (in_tree[v]) continue;
      const double mi = mutualInformation(n, na(u), na(v), nab(u, v));
      if (mi > best[v]) best[v] = mi, t.parent_[v] = u;
    }
    if (progress && added % 256 == 0)
      progress(images.size() + added * images.size() / words, images.size() * 2);
  }
  t.p1_.resize(words);
  t.p1_given0_.resize(words);
  t.p1_given1_.resize(words);
  for (uint32_t v = 0; v < words; ++v) {
    t.p1_[v] = na(v) / n;
    const uint32_t p = t.parent_[v];
    if (v == t.root_) {
      t.p1_given0_[v] = t.p1_given1_[v] = t.p1_[v];
      continue;
    }
    const double both = nab(v, p);
    t.p1_given1_[v] = both / na(p);
    t.p1_given0_[v] = (na(v) - both) / (n - na(p));
  }
  t.parent_[t.root_] = t.root_;
  return t;
}

void ChowLiuTree::write(ModelWriter& w) const {
  w.section("CLRT", std::vector<uint32_t>{root_});
  w.section("CLPA", parent_);
  w.section("CLP1", p1_);
  w.section("CLC0", p1_given0_);
  w.section("CLC1", p1_given1_);
}

ChowLiuTree ChowLiuTree::read(ModelReader& r) {
  ChowLiuTree t;
  const auto root = r.section<uint32_t>("CLRT");
  t.parent_ = r.section<uint32_t>("CLPA");
  t.p1_ = r.section<double>("CLP1");
  t.p1_given0_ = r.section<double>("CLC0");
  t.p1_given1_ = r.section<double>("CLC1");
  const size_t n = t.parent_.size();
  bool ok = root.size() == 1 && root[0] < n && t.p1_.size() == n && t.p1_given0_.size() == n &&
            t.p1_given1_.size() == n;
  for (size_t i = 0; ok && i < n; ++i) ok = t.parent_[i] < n;
  if (!ok) throw PlaceError(r.path() + ": Chow-Liu tree sections are inconsistent");
  t.root_ = root[0];
  return t;
}

}  // namespace binloop
