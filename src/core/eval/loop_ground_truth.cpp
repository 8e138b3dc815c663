#include "binloop/eval/loop_ground_truth.h"

namespace binloop {

std::vector<std::pair<int, int>> loopPairsFromPoses(const std::vector<Pose3>& T_w_c, double radius_m,
                                                    int min_frame_gap) {
  std::vector<std::pair<int, int>> pairs;
  const double r2 = radius_m * radius_m;
  const int n = static_cast<int>(T_w_c.size());
  for (int q = 0; q < n; ++q) {
    for (int r = 0; r + min_frame_gap < q; ++r)
      if ((T_w_c[q].translation() - T_w_c[r].translation()).squaredNorm() < r2) pairs.emplace_back(q, r);
  }
  return pairs;
}

}  // namespace binloop
