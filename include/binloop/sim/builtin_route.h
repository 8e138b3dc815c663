#pragma once
// A route that needs no data files: laps of a rounded rectangle, so that a machine without KITTI ground
// truth still gets a sequence with loops (the demo's default when ../shared/data is absent).
#include <vector>

#include "binloop/types/pose.h"

namespace binloop::sim {

/// T_w_c at `hz` while driving `laps` (fractional allowed) of a `width_m` x `length_m` block with corner
/// radius `radius_m` at `speed_mps`, starting at the origin looking along +z (KITTI's convention).
std::vector<Pose3> loopRoute(double width_m = 120, double length_m = 200, double radius_m = 15,
                             double speed_mps = 8, double hz = 10, double laps = 1.3);

}  // namespace binloop::sim
