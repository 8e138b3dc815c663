#pragma once
// The graph that loop correction optimises (ORB-SLAM2's essential graph): every keyframe, linked by its
// spanning-tree edge, its strong covisibility edges (weight >= min_covisibility), the loops closed before,
// and the new loop. Edge measurements are the keyframes' relative poses as they are now (what odometry and
// local BA agree on), except the new loop's, which is what verification measured; optimising then spreads
// the loop's discrepancy over the whole graph instead of tearing the map at the loop.
#include <vector>

#include "binloop/messages/map_state.h"
#include "binloop/optim/pose_graph.h"

namespace binloop {

struct LoopEdge {
  SlamKeyframeId query = kNoId, candidate = kNoId;
  Pose3 T_query_candidate = Pose3::Identity();
};

struct EssentialGraphParams {
  int min_covisibility = 100;                         // ORB-SLAM2
  double sigma_rot_rad = 0.01, sigma_trans_m = 0.05;  // odometry-like edges
  double loop_sigma_rot_rad = 0.01, loop_sigma_trans_m = 0.05;
};

struct EssentialGraph {
  std::vector<PoseGraphNode> nodes;  // one per keyframe, in the order given; `fixed` as asked
  std::vector<PoseGraphEdge> edges;
  size_t new_loop_edge = 0;  // index in edges
  int tree_edges = 0, covisibility_edges = 0, old_loop_edges = 0;
};

/// `fixed`: keyframes that do not move (the first keyframe; ORB-SLAM2 also holds the loop candidate).
/// Edges naming keyframes not in `keyframes` are left out. Throws std::invalid_argument when the new loop
/// names such a keyframe.
EssentialGraph buildEssentialGraph(const std::vector<msg::KeyframeState>& keyframes,
                                   const std::vector<LoopEdge>& old_loops, const LoopEdge& new_loop,
                                   const std::vector<SlamKeyframeId>& fixed,
                                   const EssentialGraphParams& p = {});

}  // namespace binloop
