#include "binloop/eval/slam_evaluation.h"

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
  for (int f : {query, match})
    if (f < 0 || f >= n)
      throw DataError("loop " + std::to_string(query) + " -> " + std::to_string(match) + ": frame " + std::to_string(f) +
                      " is outside the " + std::to_string(n) + " ground-truth poses");
  return (gt[query].translation() - gt[match].translation()).norm() <= radius_m;
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

}  // namespace binloop
