#pragma once
// One observation in a Ceres optimiser (private to src/core/optim; bundle adjustment has its own,
// schur_lm.h): its cost, stereo or mono, and its outlier threshold. `Stereo` and `Mono` are the
// AutoDiffCostFunction types; their functors' chi2() take the parameter blocks and then `bool* in_front`.
#include <ceres/cost_function.h>

#include <memory>

#include "optim_checks.h"

namespace binloop::optim_detail {

template <typename Stereo, typename Mono>
struct ObservationTerm {
  std::unique_ptr<Stereo> stereo;
  std::unique_ptr<Mono> mono;
  double chi2_max = 0;

  ceres::CostFunction* cost() const {
    return stereo ? static_cast<ceres::CostFunction*>(stereo.get()) : mono.get();
  }
  /// chi2(blocks..., &in_front)
  template <typename... Args>
  double chi2(Args... args) const {
    return stereo ? stereo->functor().chi2(args...) : mono->functor().chi2(args...);
  }
  /// Behind the camera, or chi2 above the threshold (or not a number).
  template <typename... Blocks>
  bool isOutlier(Blocks... blocks) const {
    bool in_front = false;
    const double c = chi2(blocks..., &in_front);
    return optim_detail::isOutlier(in_front, c, chi2_max);
  }
};

}  // namespace binloop::optim_detail
