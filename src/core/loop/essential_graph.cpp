#include "binloop/loop/essential_graph.h"

#include <algorithm>
#include <set>
#include <stdexcept>
#include <unordered_map>

namespace binloop {

EssentialGraph buildEssentialGraph(const std::vector<msg::KeyframeState>& keyframes,
                                   const std::vector<LoopEdge>& old_loops, const LoopEdge& new_loop,
                                   const std::vector<SlamKeyframeId>& fixed, const EssentialGraphParams& p) {
  EssentialGraph g;
  std::unordered_map<SlamKeyframeId, size_t> index;
  for (const msg::KeyframeState& k : keyframes) {
    index[k.id] = g.nodes.size();
    const bool hold = std::find(fixed.begin(), fixed.end(), k.id) != fixed.end();
    g.nodes.push_back({k.id, k.T_w_c.inverse(), hold});
  }
  std::set<std::pair<size_t, size_t>> linked;  // each pair once, whichever way it was met
  auto add = [&](size_t i, size_t j, const Pose3& T_i_j, double sr, double st, bool robust) {
    if (i == j || !linked.insert({std::min(i, j), std::max(i, j)}).second) return false;
    PoseGraphEdge e;
    e.i = i;
    e.j = j;
    e.T_i_j = T_i_j;
    e.sigma_rot_rad = sr;
    e.sigma_trans_m = st;
    e.robust = robust;
    g.edges.push_back(e);
    return true;
  };
  auto current = [&](size_t i, size_t j) { return g.nodes[i].T_c_w * g.nodes[j].T_c_w.inverse(); };
  // The new loop first, so that no older edge between the same pair replaces its measurement.
  const auto q = index.find(new_loop.query), c = index.find(new_loop.candidate);
  if (q == index.end() || c == index.end())
    throw std::invalid_argument("essential graph: the new loop names a keyframe that is not in the graph");
  add(q->second, c->second, new_loop.T_query_candidate, p.loop_sigma_rot_rad, p.loop_sigma_trans_m, true);
  g.new_loop_edge = 0;
  for (const LoopEdge& l : old_loops) {
    const auto a = index.find(l.query), b = index.find(l.candidate);
    if (a == index.end() || b == index.end()) continue;
    g.old_loop_edges +=
        add(a->second, b->second, current(a->second, b->second), p.sigma_rot_rad, p.sigma_trans_m, false);
  }
  for (const msg::KeyframeState& k : keyframes) {
    const size_t i = index.at(k.id);
    auto parent = index.find(k.parent);
    if (parent != index.end()) {
      g.tree_edges +=
          add(parent->second, i, current(parent->second, i), p.sigma_rot_rad, p.sigma_trans_m, false);
    }
    for (const msg::CovisibleEdge& e : k.covisible) {
      if (static_cast<int>(e.weight) < p.min_covisibility) continue;
      auto o = index.find(e.id);
      if (o == index.end()) continue;
      g.covisibility_edges +=
          add(i, o->second, current(i, o->second), p.sigma_rot_rad, p.sigma_trans_m, false);
    }
  }
  return g;
}

}  // namespace binloop
