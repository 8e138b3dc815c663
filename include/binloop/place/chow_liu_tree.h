#pragma once
// The Chow-Liu tree of word presences (thesis eq. 3.4-3.5): the maximum spanning tree of the pairwise
// mutual information between binary word variables, learned from training images' presence sets, with the
// marginals p(z_i = 1) and conditionals p(z_i = 1 | z_parent) that FAB-MAP's likelihood needs.
#include <cstdint>
#include <vector>

#include "binloop/place/model_file.h"
#include "binloop/place/vocabulary_tree.h"

namespace binloop {

class ChowLiuTree {
 public:
  /// `images`: sorted word ids present in each training image. Counts are smoothed by `pseudo_count`
  /// so that no probability is 0 or 1.
  static ChowLiuTree learn(const std::vector<std::vector<uint32_t>>& images, uint32_t words,
                           double pseudo_count = 0.5, const ProgressFn& progress = {});
  /// Mutual information (nats) of words a and b from counts, as the tree learning uses it.
  static double mutualInformation(double n, double na, double nb, double nab);

  uint32_t words() const { return static_cast<uint32_t>(parent_.size()); }
  uint32_t root() const { return root_; }
  uint32_t parent(uint32_t i) const { return parent_[i]; }  // the root is its own parent
  double marginal(uint32_t i) const { return p1_[i]; }      // p(z_i = 1)
  /// p(z_i = 1 | z_parent = zp)
  double conditional(uint32_t i, bool zp) const { return zp ? p1_given1_[i] : p1_given0_[i]; }

  void write(ModelWriter& w) const;
  static ChowLiuTree read(ModelReader& r);

 private:
  uint32_t root_ = 0;
  std::vector<uint32_t> parent_;
  std::vector<double> p1_, p1_given0_, p1_given1_;
};

}  // namespace binloop
