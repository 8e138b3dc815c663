#include "binloop/loop/loop_verifier.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "binloop/map/keypoint_geometry.h"
#include "binloop/map/keypoint_grid.h"
#include "binloop/map/scale_pyramid.h"
#include "binloop/optim/pose_optimizer.h"
#include "binloop/place/descriptor_block.h"
#include "binloop/util/hash_random.h"

namespace binloop {

msg::LoopStatus loopStatusOf(LoopRejection r) {
  switch (r) {
    case LoopRejection::kNone:
      return msg::LoopStatus::kAccepted;
    case LoopRejection::kTooFewMatches:
      return msg::LoopStatus::kTooFewMatches;
    case LoopRejection::kNoConsensus:
      return msg::LoopStatus::kNoConsensus;
    case LoopRejection::kTooFewInliers:
      return msg::LoopStatus::kTooFewInliers;
  }
  return msg::LoopStatus::kTooFewMatches;
}

namespace {

// Pose optimisation of T_query_candidate on the pairs; drops the outliers from `pairs`.
int refine(const msg::KeyFrame& q, const msg::KeyFrame& c, const ScalePyramid& s,
           const PoseOptimizerParams& p, Pose3* T, std::vector<std::pair<int, int>>* pairs) {
  std::vector<PoseObservation> obs;
  for (const auto& [qi, ci] : *pairs) {
    const msg::KeyPoint& kq = q.keypoints[qi];
    PoseObservation o;
    o.p_w = unprojectKeypoint(c.keypoints[ci], c.camera);
    o.uv = {kq.x, kq.y};
    o.u_right = kq.right_x;
    o.inv_sigma2 = s.inv_sigma2[kq.octave];
    obs.push_back(o);
  }
  if (obs.size() < 3) return 0;
  const PoseOptimizationResult r = optimizePose(q.camera, *T, obs, p);
  *T = r.T_c_w;
  std::vector<std::pair<int, int>> kept;
  for (size_t i = 0; i < pairs->size(); ++i)
    if (!r.outlier[i]) kept.push_back((*pairs)[i]);
  *pairs = std::move(kept);
  return static_cast<int>(pairs->size());
}

// Adds to `pairs` the candidate's unpaired stereo points that, put in the query by T, land near an unpaired
// query keypoint of the scale the distance predicts, with a descriptor closer than max_hamming.
void guidedSearch(const msg::KeyFrame& q, const msg::KeyFrame& c, const ScalePyramid& s,
                  const LoopVerifierParams& p, const Pose3& T, std::vector<std::pair<int, int>>* pairs) {
  std::vector<char> q_used(q.keypoints.size(), 0), c_used(c.keypoints.size(), 0);
  for (const auto& [qi, ci] : *pairs) q_used[qi] = c_used[ci] = 1;
  const KeypointGrid grid(q.keypoints, q.camera.width, q.camera.height);
  const double log_scale = std::log(static_cast<double>(q.scale_factor));
  for (size_t j = 0; j < c.keypoints.size(); ++j) {
    if (c_used[j] || !hasStereo(c.keypoints[j])) continue;
    const Eigen::Vector3d pc = unprojectKeypoint(c.keypoints[j], c.camera);
    const Eigen::Vector3d pq = T * pc;
    if (pq.z() <= 0) continue;
    const Eigen::Vector2d uv = q.camera.project(pq);
    const float u = static_cast<float>(uv.x()), w = static_cast<float>(uv.y());
    // Seen from nearer, the same patch is found on a coarser level (ORB-SLAM2's PredictScale).
    const int shift = static_cast<int>(std::lround(std::log(pc.norm() / pq.norm()) / log_scale));
    const int level = std::clamp(c.keypoints[j].octave + shift, 0, q.levels - 1);
    const float r = p.search_radius * s.scale[level];
    int best = 256, best_i = -1;
    for (int i : grid.near(u, w, r, level - 1, level + 1)) {
      if (q_used[i]) continue;
      const int d = hamming(q.descriptors[i], c.descriptors[j]);
      if (d < best) best = d, best_i = i;
    }
    if (best_i < 0 || best > p.max_hamming) continue;
    q_used[best_i] = 1;
    pairs->emplace_back(best_i, static_cast<int>(j));
  }
}

// Descriptor matches (query keypoint, candidate keypoint) between stereo keypoints, each candidate keypoint
// used once: brute force, or within the same word when `words` (the query's) is given with the candidate's.
std::vector<std::pair<int, int>> descriptorPairs(const msg::KeyFrame& q, const msg::KeyFrame& c,
                                                 const LoopVerifierParams& p,
                                                 const std::vector<uint32_t>* words,
                                                 const std::vector<uint32_t>* candidate_words) {
  std::vector<int> best_of_c(c.keypoints.size(), -1),
      dist_of_c(c.keypoints.size(), std::numeric_limits<int>::max());
  // One block of the candidate's stereo descriptors per word (a single block when brute force).
  struct Cell {
    DescriptorBlock desc;
    std::vector<int> index;
  };
  std::unordered_map<uint32_t, Cell> cells;
  for (size_t j = 0; j < c.keypoints.size(); ++j) {
    if (!hasStereo(c.keypoints[j])) continue;
    Cell& cell = cells[words ? (*candidate_words)[j] : 0];
    cell.index.push_back(static_cast<int>(j));
    cell.desc.add(c.descriptors[j]);
  }
  for (size_t i = 0; i < q.keypoints.size(); ++i) {
    if (!hasStereo(q.keypoints[i])) continue;
    auto cell = cells.find(words ? (*words)[i] : 0);
    if (cell == cells.end()) continue;
    const DescriptorBlock::Nearest n = cell->second.desc.nearest(q.descriptors[i]);
    if (n.index < 0 || n.best > p.max_hamming || n.best > p.ratio * n.second) continue;
    const int best_j = cell->second.index[n.index];
    if (n.best < dist_of_c[best_j]) dist_of_c[best_j] = n.best, best_of_c[best_j] = static_cast<int>(i);
  }
  std::vector<std::pair<int, int>> pairs;
  for (size_t j = 0; j < c.keypoints.size(); ++j)
    if (best_of_c[j] >= 0) pairs.emplace_back(best_of_c[j], static_cast<int>(j));
  return pairs;
}

}  // namespace

LoopVerification verifyLoop(const msg::KeyFrame& q, const msg::KeyFrame& c, const LoopVerifierParams& p,
                            const std::vector<uint32_t>& query_words,
                            const std::vector<uint32_t>& candidate_words) {
  const auto t0 = std::chrono::steady_clock::now();
  LoopVerification v;
  std::string words_note;
  auto done = [&](LoopRejection r, const std::string& detail) {
    v.rejection = r;
    v.accepted = r == LoopRejection::kNone;
    v.detail = detail + words_note;
    v.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return v;
  };
  const ScalePyramid s(q.scale_factor, q.levels);

  // 1. Descriptor matches between stereo keypoints, each candidate keypoint used once.
  const bool words_fit =
      query_words.size() == q.keypoints.size() && candidate_words.size() == c.keypoints.size();
  v.by_words = p.match_by_words && words_fit;
  if (p.match_by_words && !words_fit && (!query_words.empty() || !candidate_words.empty())) {
    words_note = " (words not used: " + std::to_string(query_words.size()) + " and " +
                 std::to_string(candidate_words.size()) + " for " + std::to_string(q.keypoints.size()) +
                 " and " + std::to_string(c.keypoints.size()) + " keypoints)";
  }
  const std::vector<std::pair<int, int>> pairs =
      descriptorPairs(q, c, p, v.by_words ? &query_words : nullptr, &candidate_words);
  v.matches = static_cast<int>(pairs.size());
  auto lap = [t = std::chrono::steady_clock::now()]() mutable {
    const auto now = std::chrono::steady_clock::now();
    const double ms = std::chrono::duration<double, std::milli>(now - t).count();
    t = now;
    return ms;
  };
  v.match_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const std::string matched = std::to_string(v.matches) + (v.by_words ? " matches within words" : " matches");
  if (v.matches < p.min_matches)
    return done(LoopRejection::kTooFewMatches, matched + " < " + std::to_string(p.min_matches));

  // 2. RANSAC over Horn on the 3-D pairs.
  std::vector<Eigen::Vector3d> a, b;
  for (const auto& [qi, ci] : pairs) {
    a.push_back(unprojectKeypoint(q.keypoints[qi], q.camera));
    b.push_back(unprojectKeypoint(c.keypoints[ci], c.camera));
  }
  const RigidRansacResult rr = rigidRansac(a, b, p.ransac, hashCombine(p.seed, hashCombine(q.id, c.id)));
  v.first_inliers = rr.inliers;
  v.ransac_ms = lap();
  if (!rr.ok) {
    return done(LoopRejection::kNoConsensus, matched + ", best consensus " + std::to_string(rr.inliers) +
                                                 " < " + std::to_string(p.ransac.min_inliers));
  }
  std::vector<std::pair<int, int>> in;
  for (size_t i = 0; i < pairs.size(); ++i)
    if (rr.inlier[i]) in.push_back(pairs[i]);

  // 3. Refinement by reprojection.
  Pose3 T = rr.T_a_b;
  refine(q, c, s, p.refine, &T, &in);
  v.refine_ms = lap();

  // 4. Guided search for the candidate's other stereo points.
  guidedSearch(q, c, s, p, T, &in);
  v.inliers = refine(q, c, s, p.refine, &T, &in);
  v.guided_ms = lap();
  v.T_query_candidate = T;
  v.pairs = in;
  const std::string numbers = matched + ", " + std::to_string(v.first_inliers) + " RANSAC inliers, " +
                              std::to_string(v.inliers) + " after guided search";
  if (v.inliers < p.min_inliers)
    return done(LoopRejection::kTooFewInliers, numbers + " < " + std::to_string(p.min_inliers));
  return done(LoopRejection::kNone, numbers);
}

LoopVerification verifyLoopAt(const msg::KeyFrame& q, const msg::KeyFrame& c, const Pose3& T_guess,
                              const LoopVerifierParams& p) {
  const auto t0 = std::chrono::steady_clock::now();
  LoopVerification v;
  const ScalePyramid s(q.scale_factor, q.levels);
  Pose3 T = T_guess;
  std::vector<std::pair<int, int>> in;
  guidedSearch(q, c, s, p, T, &in);
  v.matches = static_cast<int>(in.size());
  refine(q, c, s, p.refine, &T, &in);
  v.first_inliers = static_cast<int>(in.size());
  guidedSearch(q, c, s, p, T, &in);
  v.inliers = refine(q, c, s, p.refine, &T, &in);
  v.T_query_candidate = T;
  v.pairs = in;
  v.accepted = v.inliers >= p.min_inliers;
  v.rejection = v.accepted ? LoopRejection::kNone : LoopRejection::kTooFewInliers;
  v.detail = std::to_string(v.matches) + " matches by projection, " + std::to_string(v.first_inliers) +
             " after refinement, " + std::to_string(v.inliers) + " after a second search" +
             (v.accepted ? "" : " < " + std::to_string(p.min_inliers));
  v.ms = v.guided_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return v;
}

}  // namespace binloop
