#include "binloop/optim/pose_graph.h"

#include <gtest/gtest.h>

#include "optim_test_scene.h"

namespace binloop {
namespace {

// 40 keyframes around a 40 x 40 m block (T_w_c), odometry edges with a small yaw bias (drift), and one
// loop edge from the last keyframe back to the first with the true relative pose.
struct Loop {
  std::vector<Pose3> truth;  // T_w_c
  std::vector<PoseGraphNode> nodes;
  std::vector<PoseGraphEdge> edges;
};

Loop makeLoop(bool with_loop_edge) {
  Loop l;
  const int n = 40;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * test::kPi * i / n;
    Pose3 T = Pose3::Identity();
    T.linear() = Eigen::AngleAxisd(-a, Eigen::Vector3d::UnitY()).toRotationMatrix();
    T.translation() = Eigen::Vector3d(20 * std::sin(a), 0, 20 - 20 * std::cos(a));
    l.truth.push_back(T);
  }
  // Dead reckoning with a biased yaw: what the nodes start from.
  const Pose3 bias(Eigen::AngleAxisd(0.004, Eigen::Vector3d::UnitY()));
  Pose3 est = l.truth[0];
  for (int i = 0; i < n; ++i) {
    if (i > 0) est = est * (l.truth[i - 1].inverse() * l.truth[i]) * bias;
    l.nodes.push_back({static_cast<uint64_t>(i), est.inverse(), i == 0});
  }
  for (int i = 1; i < n; ++i) {
    PoseGraphEdge e;
    e.i = static_cast<size_t>(i - 1);
    e.j = static_cast<size_t>(i);
    e.T_i_j = l.truth[i - 1].inverse() * l.truth[i] * bias;  // the odometry, biased
    l.edges.push_back(e);
  }
  if (with_loop_edge) {
    PoseGraphEdge loop;
    loop.i = n - 1;
    loop.j = 0;
    loop.T_i_j = l.truth[n - 1].inverse() * l.truth[0];
    loop.robust = true;
    l.edges.push_back(loop);
  }
  return l;
}

double meanError(const Loop& l, const std::vector<Pose3>& T_c_w) {
  double e = 0;
  for (size_t i = 0; i < l.truth.size(); ++i)
    e += (T_c_w[i].inverse().translation() - l.truth[i].translation()).norm();
  return e / static_cast<double>(l.truth.size());
}

TEST(PoseGraph, ALoopEdgeTakesOutMostOfTheDrift) {
  const Loop l = makeLoop(true);
  std::vector<Pose3> start;
  for (const auto& n : l.nodes) start.push_back(n.T_c_w);
  const double before = meanError(l, start);
  const PoseGraphResult r = optimizePoseGraph(l.nodes, l.edges);
  const double after = meanError(l, r.T_c_w);
  EXPECT_GT(before, 1.0) << "the scenario needs drift";
  EXPECT_LT(after, 0.25 * before) << "before " << before << " m, after " << after << " m";
  EXPECT_LT(r.final_cost, r.initial_cost);
  EXPECT_TRUE(r.T_c_w[0].isApprox(l.nodes[0].T_c_w, 0)) << "the fixed node does not move";
  EXPECT_EQ(r.edge_chi2.size(), l.edges.size());
}

TEST(PoseGraph, WithoutALoopEdgeNothingMoves) {
  const Loop l = makeLoop(false);
  const PoseGraphResult r = optimizePoseGraph(l.nodes, l.edges);
  for (size_t i = 0; i < l.nodes.size(); ++i)
    EXPECT_LT((r.T_c_w[i].inverse().translation() - l.nodes[i].T_c_w.inverse().translation()).norm(), 1e-6)
        << i;
}

TEST(PoseGraph, AWrongLoopEdgeKeepsALargeResidual) {
  Loop l = makeLoop(true);
  l.edges.back().T_i_j.translation() += Eigen::Vector3d(15, 0, 0);  // a look-alike 15 m away
  const PoseGraphResult r = optimizePoseGraph(l.nodes, l.edges);
  EXPECT_GT(r.edge_chi2.back(), 100.0) << "the guard of the loop closer reads this";
}

TEST(PoseGraph, BadGraphsAreRefused) {
  Loop l = makeLoop(true);
  for (auto& n : l.nodes) n.fixed = false;
  EXPECT_THROW(optimizePoseGraph(l.nodes, l.edges), std::invalid_argument);
  l = makeLoop(true);
  l.edges[0].j = 99;
  EXPECT_THROW(optimizePoseGraph(l.nodes, l.edges), std::invalid_argument);
}

}  // namespace
}  // namespace binloop
