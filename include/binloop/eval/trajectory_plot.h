#pragma once
// A top view of a trajectory against its ground truth, as one PNG (OpenCV drawing, no plotting library).
#include <string>
#include <utility>
#include <vector>

#include "binloop/eval/trajectory_metrics.h"
#include "binloop/types/pose.h"

namespace binloop {

/// Draws the x-z plane of camera 0's first frame (KITTI: x right, z forward; z points up the image, so
/// this is the view from above): `gt` (every ground-truth pose) and `est_aligned` (the estimate already
/// mapped into the ground truth's frame, e.g. by metrics.T_gt_est) with equal axis scales, a start marker,
/// a scale bar, a legend, and the metrics as text. Throws DataError when the file cannot be written.
void writeTrajectoryPlot(const std::string& path, const std::string& title, const std::vector<Pose3>& gt,
                         const std::vector<Pose3>& est_aligned, const TrajectoryMetrics& metrics);

/// The same top view of several estimates over one ground truth (eval-slam): each (label, poses) already
/// aligned into the ground truth's frame, each in its own colour with its label in the legend.
void writeTrajectoriesPlot(const std::string& path, const std::string& title, const std::vector<Pose3>& gt,
                           const std::vector<std::pair<std::string, std::vector<Pose3>>>& aligned);

}  // namespace binloop
