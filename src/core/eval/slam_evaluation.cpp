#include "binloop/eval/slam_evaluation.h"

#include <cmath>
#include <set>

#include "binloop/io/data_error.h"

namespace binloop {

std::vector<RevisitSegment> revisitSegments(const std::vector<std::pair<int, int>>& pairs, int max_gap) {
  std::set<int> queries;
  for (const auto& pr : pairs) queries.insert(pr.first);
  std::vector<RevisitSegment> segments;
  for (int q : queries) {
    if (segments.empty() || q - segments.back().last > max_gap) segments.push_back({q, q, 0});
    segments.back().last = q;
    ++segments.back().queries;
  }
  return segments;
}

bool loopIsCorrect(int query, int match, const std::vector<Pose3>& gt, double radius_m) {
  const int n = static_cast<int>(gt.size());
  for (int f : {query, match}) {
    if (f < 0 || f >= n) {
      throw DataError("loop " + std::to_string(query) + " -> " + std::to_string(match) + ": frame " +
                      std::to_string(f) + " is outside the " + std::to_string(n) + " ground-truth poses");
    }
  }
  return (gt[query].translation() - gt[match].translation()).norm() <= radius_m;
}

LoopPoseError loopPoseError(int query, int match, const Pose3& T_query_match, const std::vector<Pose3>& gt) {
  loopIsCorrect(query, match, gt);  // checks the frames
  const Pose3 truth = gt[query].inverse() * gt[match];
  const Pose3 diff = truth.inverse() * T_query_match;
  LoopPoseError e;
  e.translation_m = diff.translation().norm();
  e.rotation_deg = rotationDeg(diff.linear());
  return e;
}

int LoopScore::segmentsClosed() const {
  int n = 0;
  for (bool c : closed) n += c;
  return n;
}

LoopScore scoreLoops(const std::vector<std::pair<int, int>>& accepted, const std::vector<Pose3>& gt,
                     const std::vector<RevisitSegment>& segments, double radius_m) {
  LoopScore s;
  s.closed.assign(segments.size(), false);
  for (const auto& [query, match] : accepted) {
    ++s.accepted;
    if (!loopIsCorrect(query, match, gt, radius_m)) continue;  // a wrong loop closes nothing
    ++s.correct;
    for (size_t i = 0; i < segments.size(); ++i)
      if (query >= segments[i].first && query <= segments[i].last) s.closed[i] = true;
  }
  return s;
}

LoopScore scoreLoops(const std::vector<std::pair<int, int>>& accepted,
                     const std::vector<Pose3>& T_query_match, const std::vector<Pose3>& gt,
                     const std::vector<RevisitSegment>& segments, double radius_m) {
  if (T_query_match.size() != accepted.size()) {
    throw DataError("scoring loops: " + std::to_string(accepted.size()) + " loops but " +
                    std::to_string(T_query_match.size()) + " relative poses");
  }
  std::vector<std::pair<int, int>> right_pose;
  int wrong = 0;
  for (size_t i = 0; i < accepted.size(); ++i) {
    if (loopPoseIsWrong(loopPoseError(accepted[i].first, accepted[i].second, T_query_match[i], gt))) {
      ++wrong;
    } else {
      right_pose.push_back(accepted[i]);
    }
  }
  LoopScore s = scoreLoops(right_pose, gt, segments, radius_m);
  s.accepted += wrong;
  s.wrong_pose = wrong;
  return s;
}

}  // namespace binloop
