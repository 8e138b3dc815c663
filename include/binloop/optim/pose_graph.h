#pragma once
// Pose-graph optimisation for loop correction (ORB-SLAM2's OptimizeEssentialGraph, with SE3 instead of Sim3
// because stereo fixes the scale). Nodes are keyframe poses; edges are measured relative poses (spanning
// tree, strong covisibility, loop edges). Each node is the 6-vector increment of optim/reprojection_costs.h
// on its starting pose, so a fixed node comes back bit-identical.
//
// Edge residual. With T_i = T_ci_w, the edge predicts T_ij = T_i T_j^-1 (camera j in camera i). For a
// measurement M_ij, the error E = M_ij^-1 T_ij, and
//     r = ( Log(R_E) / sigma_rot ,  t_E / sigma_trans )     (6 rows; Log as an angle-axis vector)
// so |r|^2 is a chi2 with 6 dof when the sigmas are the measurement's standard deviations. Ceres
// minimises 1/2 sum rho(|r|^2) with a Huber loss on the loop edges only (odometry edges are trusted).
#include <cstdint>
#include <vector>

#include "binloop/types/pose.h"

namespace binloop {

struct PoseGraphNode {
  uint64_t id = 0;
  Pose3 T_c_w = Pose3::Identity();
  bool fixed = false;
};

struct PoseGraphEdge {
  size_t i = 0, j = 0;              // node indices
  Pose3 T_i_j = Pose3::Identity();  // measured pose of camera j in camera i
  double sigma_rot_rad = 0.01;
  double sigma_trans_m = 0.05;
  bool robust = false;  // Huber loss (loop edges)
};

struct PoseGraphParams {
  int max_iterations = 30;
  double huber_delta = 3.0;  // on sqrt(chi2) of a robust edge
  // Stop when an iteration changes the cost by less than this share: a loop's chi2 falls by 4-6 orders of
  // magnitude in the first few iterations, and the last ones (Ceres' default 1e-6) move keyframes by
  // millimetres.
  double function_tolerance = 1e-4;
  // Levenberg-Marquardt's first trust region. Ceres' default (1e4) damps the first steps of a graph that
  // starts from odometry, which is already close; starting almost as Gauss-Newton halves the iterations
  // (250-keyframe loop: 9 -> 4, 100 -> 56 ms; 1400 keyframes: 16 -> 6; bench/closing_bench.cpp).
  double initial_trust_region = 1e8;
};

struct PoseGraphResult {
  std::vector<Pose3> T_c_w;               // per node
  std::vector<double> edge_chi2;          // per edge, at the solution
  std::vector<double> initial_edge_chi2;  // per edge, at the starting poses
  double initial_cost = 0, final_cost = 0;
  int iterations = 0;
  bool converged = false;
};

/// Throws std::invalid_argument for an edge naming a node out of range or no fixed node (the graph would
/// float). Deterministic (one thread).
PoseGraphResult optimizePoseGraph(const std::vector<PoseGraphNode>& nodes,
                                  const std::vector<PoseGraphEdge>& edges, const PoseGraphParams& p = {});

}  // namespace binloop
