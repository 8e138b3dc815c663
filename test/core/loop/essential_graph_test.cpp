#include "binloop/loop/essential_graph.h"

#include <gtest/gtest.h>

#include "../optim/optim_test_scene.h"

namespace binloop {
namespace {

// 40 keyframes around a 40 x 40 m block whose poses drifted in yaw; each is the child of the one before and
// covisible with it (150 points) and with the one before that (50, below the essential graph's 100).
struct Drifted {
  std::vector<Pose3> truth;
  std::vector<msg::KeyframeState> states;
};

Drifted drifted() {
  Drifted d;
  const int n = 40;
  const Pose3 bias(Eigen::AngleAxisd(0.004, Eigen::Vector3d::UnitY()));
  Pose3 est = Pose3::Identity();
  for (int i = 0; i < n; ++i) {
    const double a = 2 * test::kPi * i / n;
    Pose3 T = Pose3::Identity();
    T.linear() = Eigen::AngleAxisd(-a, Eigen::Vector3d::UnitY()).toRotationMatrix();
    T.translation() = Eigen::Vector3d(20 * std::sin(a), 0, 20 - 20 * std::cos(a));
    if (i > 0) est = est * (d.truth.back().inverse() * T) * bias;
    d.truth.push_back(T);
    msg::KeyframeState s;
    s.id = 100 + i;
    s.T_w_c = i == 0 ? T : est;
    if (i > 0) {
      s.parent = 100 + i - 1;
      s.covisible.push_back({static_cast<SlamKeyframeId>(100 + i - 1), 150});
    }
    if (i > 1) s.covisible.push_back({static_cast<SlamKeyframeId>(100 + i - 2), 50});
    d.states.push_back(s);
  }
  return d;
}

TEST(EssentialGraph, HoldsTreeStrongCovisibilityAndLoopsOnceEach) {
  const Drifted d = drifted();
  const LoopEdge old{110, 105, d.states[5].T_w_c.inverse() * d.states[10].T_w_c};  // as now: no news
  const LoopEdge loop{139, 100, d.truth[39].inverse() * d.truth[0]};
  const EssentialGraph g = buildEssentialGraph(d.states, {old}, loop, {100});
  EXPECT_EQ(g.nodes.size(), 40u);
  EXPECT_EQ(g.tree_edges, 39);
  EXPECT_EQ(g.covisibility_edges, 0) << "the strong ones are tree edges already, the weak ones stay out";
  EXPECT_EQ(g.old_loop_edges, 1);
  EXPECT_EQ(g.edges.size(), 41u);
  EXPECT_TRUE(g.edges[g.new_loop_edge].robust);
  EXPECT_TRUE(g.nodes[0].fixed);
  EXPECT_FALSE(g.nodes[1].fixed);
}

TEST(EssentialGraph, OptimisingItClosesTheLoop) {
  const Drifted d = drifted();
  const LoopEdge loop{139, 100, d.truth[39].inverse() * d.truth[0]};
  const EssentialGraph g = buildEssentialGraph(d.states, {}, loop, {100});
  const PoseGraphResult r = optimizePoseGraph(g.nodes, g.edges);
  double before = 0, after = 0;
  for (size_t i = 0; i < d.truth.size(); ++i) {
    before += (d.states[i].T_w_c.translation() - d.truth[i].translation()).norm();
    after += (r.T_c_w[i].inverse().translation() - d.truth[i].translation()).norm();
  }
  EXPECT_LT(after, 0.25 * before) << "mean " << before / 40 << " -> " << after / 40 << " m";
  EXPECT_LT(r.edge_chi2[g.new_loop_edge], 10.0);
}

TEST(EssentialGraph, ALoopToAnUnknownKeyframeIsRefused) {
  const Drifted d = drifted();
  EXPECT_THROW(buildEssentialGraph(d.states, {}, LoopEdge{139, 999, Pose3::Identity()}, {100}),
               std::invalid_argument);
}

}  // namespace
}  // namespace binloop
