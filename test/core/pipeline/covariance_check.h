#pragma once
// How well tracked frames' pose covariances predict their real error: the error of the motion between
// consecutive frames (the map's own error, shared by both, mostly cancels there) against the two frames'
// predicted position variances.
#include <cmath>
#include <vector>

#include "binloop/messages/tracked_frame.h"
#include "binloop/types/pose.h"

namespace binloop::test {

struct CovarianceCheck {
  int steps = 0;  // consecutive pairs with both covariances known
  double rms_error_m = 0, predicted_sd_m = 0;
  double ratio = 0;  // summed squared errors / summed predicted variances: 1 when the covariance is right
};

/// `truth[i]` is the true T_w_c of `frames[i]`.
inline CovarianceCheck checkCovariances(const std::vector<msg::TrackedFrame>& frames,
                                        const std::vector<Pose3>& truth) {
  CovarianceCheck c;
  double err2 = 0, predicted = 0;
  for (size_t k = 1; k < frames.size() && k < truth.size(); ++k) {
    const msg::TrackedFrame &a = frames[k - 1], &b = frames[k];
    if (a.pose_covariance.isZero(0) || b.pose_covariance.isZero(0)) continue;
    const Pose3 est = a.T_w_c.inverse() * b.T_w_c, real = truth[k - 1].inverse() * truth[k];
    err2 += (est.translation() - real.translation()).squaredNorm();
    predicted +=
        a.pose_covariance.topLeftCorner<3, 3>().trace() + b.pose_covariance.topLeftCorner<3, 3>().trace();
    ++c.steps;
  }
  if (c.steps == 0) return c;
  c.rms_error_m = std::sqrt(err2 / c.steps);
  c.predicted_sd_m = std::sqrt(predicted / c.steps);
  c.ratio = err2 / predicted;
  return c;
}

}  // namespace binloop::test
