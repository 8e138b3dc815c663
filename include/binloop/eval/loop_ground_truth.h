#pragma once
// Ground-truth loop pairs from poses, the project's definition: frames within `radius_m` metres of each other
// that are more than `min_frame_gap` frames apart (not temporal neighbours). The KITTI lists in
// ../shared/data/kitti/loop_gt were made the same way (6 m); this makes them for any sequence with poses,
// such as a rendered route or the built-in loop.
#include <utility>
#include <vector>

#include "binloop/types/pose.h"

namespace binloop {

/// (query, ref) pairs with query > ref + min_frame_gap, ordered by query then ref.
std::vector<std::pair<int, int>> loopPairsFromPoses(const std::vector<Pose3>& T_w_c, double radius_m,
                                                    int min_frame_gap);

}  // namespace binloop
