#include "binloop/loop/essential_graph.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>
#include <unordered_map>

namespace binloop {
namespace {

uint32_t sharedPoints(const msg::KeyframeState& k, SlamKeyframeId other) {
  for (const msg::CovisibleEdge& e : k.covisible)
    if (e.id == other) return e.weight;
  return 0;
}

// The median weight of the tree and strong covisibility edges: the weight whose edge keeps the base sigmas.
double medianWeight(const std::vector<msg::KeyframeState>& keyframes, int min_covisibility) {
  std::vector<uint32_t> w;
  for (const msg::KeyframeState& k : keyframes) {
    if (const uint32_t t = sharedPoints(k, k.parent)) w.push_back(t);
    for (const msg::CovisibleEdge& e : k.covisible)
      if (static_cast<int>(e.weight) >= min_covisibility && e.id != k.parent) w.push_back(e.weight);
  }
  if (w.empty()) return 0;
  std::nth_element(w.begin(), w.begin() + w.size() / 2, w.end());
  return w[w.size() / 2];
}

}  // namespace

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
  const double median = p.weight_by_covisibility ? medianWeight(keyframes, p.min_covisibility) : 0;
  auto odometry = [&](size_t i, size_t j, uint32_t weight) {
    double f = 1;
    if (median > 0 && weight > 0) {
      f = std::clamp(std::sqrt(median / weight), 1 / EssentialGraphParams::kMaxSigmaScale,
                     EssentialGraphParams::kMaxSigmaScale);
    }
    return add(i, j, current(i, j), f * p.sigma_rot_rad, f * p.sigma_trans_m, false);
  };
  for (const msg::KeyframeState& k : keyframes) {
    const size_t i = index.at(k.id);
    auto parent = index.find(k.parent);
    if (parent != index.end()) g.tree_edges += odometry(parent->second, i, sharedPoints(k, k.parent));
    for (const msg::CovisibleEdge& e : k.covisible) {
      if (static_cast<int>(e.weight) < p.min_covisibility) continue;
      auto o = index.find(e.id);
      if (o == index.end()) continue;
      g.covisibility_edges += odometry(i, o->second, e.weight);
    }
  }
  return g;
}

}  // namespace binloop
