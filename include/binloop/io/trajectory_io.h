#pragma once
// Trajectory files. KITTI: 12 numbers per line, the first three rows of T_w_c, row-major, no time.
// TUM: "stamp tx ty tz qx qy qz qw".
#include <string>
#include <vector>

#include "binloop/types/pose.h"

namespace binloop {

std::vector<Pose3> readKittiPoses(const std::string& path);
void writeKittiPoses(const std::string& path, const std::vector<Pose3>& poses);

Trajectory readTumTrajectory(const std::string& path);
void writeTumTrajectory(const std::string& path, const Trajectory& traj);

/// One number per line (KITTI times.txt).
std::vector<double> readTimes(const std::string& path);
void writeTimes(const std::string& path, const std::vector<double>& times);

/// Pairs "query ref" per line (loop ground truth), '#' comments allowed.
std::vector<std::pair<int, int>> readIndexPairs(const std::string& path);

}  // namespace binloop
