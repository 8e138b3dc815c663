#include "binloop/eval/turn_tilt.h"

#include <cmath>
#include <map>

namespace binloop {

namespace {

double turnDeg(const Pose3& a, const Pose3& b) { return rotationDeg(a.linear().transpose() * b.linear()); }

// How the estimate's rotation from frame a to frame b is off the truth's, as a rotation vector in the truth's
// world (degrees). It compares motions, not poses, so the estimate's own world frame drops out: a run started
// mid-route, whose world is that frame's camera, is measured as one started at frame 0.
Eigen::Vector3d errorGained(const Pose3& gt_a, const Pose3& est_a, const Pose3& gt_b, const Pose3& est_b) {
  const Eigen::AngleAxisd aa(gt_a.linear() * (est_a.linear().transpose() * est_b.linear()) *
                             gt_b.linear().transpose());
  return aa.axis() * aa.angle() * 180.0 / M_PI;
}

}  // namespace

std::vector<SharpTurn> sharpTurns(const std::vector<Pose3>& truth, const SharpTurnParams& p) {
  std::vector<SharpTurn> out;
  const int n = static_cast<int>(truth.size());
  int i = 0;
  while (i + 1 < n) {
    if (turnDeg(truth[i], truth[i + 1]) <= p.start_deg_per_frame) {
      ++i;
      continue;
    }
    int j = i;
    while (j + 1 < n && turnDeg(truth[j], truth[j + 1]) > p.keep_deg_per_frame) ++j;
    if (j - i >= p.min_frames)
      out.push_back({std::max(0, i - p.pad_frames), std::min(n - 1, j + p.pad_frames)});
    i = j + 1;
  }
  return out;
}

std::vector<TurnTilt> tiltLeftByTurns(const MatchedPoses& m, const std::vector<SharpTurn>& turns) {
  std::map<int, size_t> at;  // frame -> pair
  for (size_t k = 0; k < m.frames.size(); ++k) at[m.frames[k]] = k;
  std::vector<TurnTilt> out;
  for (const SharpTurn& t : turns) {
    const auto a = at.find(t.first), b = at.find(t.last);
    if (a == at.end() || b == at.end()) continue;
    const Eigen::Vector3d d =
        errorGained(m.gt[a->second], m.est[a->second], m.gt[b->second], m.est[b->second]);
    out.push_back({t, std::hypot(d.x(), d.z())});
  }
  return out;
}

}  // namespace binloop
