#include "binloop/eval/trajectory_metrics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>

#include <Eigen/SVD>

#include "binloop/io/data_error.h"
#include "binloop/io/number_lines.h"
#include "binloop/io/trajectory_io.h"

namespace binloop {

namespace {

std::string num(double v, const char* fmt = "%.6g") {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

// The pose readers let NaN through (every comparison with NaN is false), so files are screened first.
std::vector<NumberLine> readFinitePoseLines(const std::string& path) {
  auto lines = readNumberLines(path);
  if (lines.empty()) throw dataError(path, 0, "holds no poses");
  for (const auto& l : lines) {
    for (double v : l.values) {
      if (!std::isfinite(v))
        throw dataError(path, l.line_no, "holds a number that is not finite (" + num(v) + ")");
    }
  }
  return lines;
}

bool finitePose(const Pose3& T) { return T.matrix().allFinite(); }

MatchedPoses assemble(const std::vector<Pose3>& gt, const EstimateFile& est, std::vector<int> frame_of,
                      const std::string& source) {
  std::vector<size_t> order(frame_of.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return frame_of[a] < frame_of[b]; });
  MatchedPoses m;
  m.gt_frames = gt.size();
  for (size_t k = 0; k < order.size(); ++k) {
    const size_t i = order[k];
    if (k > 0 && frame_of[i] == m.frames.back()) {
      throw DataError(source + ": poses " + std::to_string(order[k - 1] + 1) + " and " +
                      std::to_string(i + 1) + " both match ground-truth frame " +
                      std::to_string(frame_of[i]));
    }
    m.frames.push_back(frame_of[i]);
    m.gt.push_back(gt[frame_of[i]]);
    m.est.push_back(est.poses[i].T_w_c);
  }
  return m;
}

}  // namespace

const char* formatName(TrajectoryFormat f) { return f == TrajectoryFormat::kitti ? "KITTI" : "TUM"; }

EstimateFile readEstimateFile(const std::string& path) {
  const auto lines = readFinitePoseLines(path);
  const size_t n = lines.front().values.size();
  if (n != 12 && n != 8) {
    throw dataError(path, lines.front().line_no,
                    "a pose line needs 12 numbers (KITTI) or 8 (TUM: stamp tx ty tz qx qy qz qw), found " +
                        std::to_string(n));
  }
  for (const auto& l : lines) {
    if (l.values.size() != n) {
      throw dataError(path, l.line_no,
                      "has " + std::to_string(l.values.size()) + " numbers, but the first pose line has " +
                          std::to_string(n) + (n == 12 ? " (KITTI)" : " (TUM)"));
    }
  }
  EstimateFile f;
  if (n == 12) {
    f.format = TrajectoryFormat::kitti;
    const auto poses = readKittiPoses(path);
    for (size_t i = 0; i < poses.size(); ++i) f.poses.push_back({static_cast<double>(i), poses[i]});
  } else {
    f.format = TrajectoryFormat::tum;
    f.poses = readTumTrajectory(path);
  }
  return f;
}

std::vector<Pose3> readGroundTruthPoses(const std::string& path) {
  readFinitePoseLines(path);
  return readKittiPoses(path);
}

MatchedPoses matchByFrameIndex(const std::vector<Pose3>& gt, const EstimateFile& est,
                               const std::string& source) {
  const bool kitti = est.format == TrajectoryFormat::kitti;
  if (kitti && est.poses.size() > gt.size()) {
    throw DataError(source + ": " + std::to_string(est.poses.size()) +
                    " poses, but the ground truth has only " + std::to_string(gt.size()) +
                    " (KITTI lines are matched to frames by position)");
  }
  std::vector<int> frame_of;
  for (size_t i = 0; i < est.poses.size(); ++i) {
    const double s = est.poses[i].stamp_s;
    if (std::abs(s - std::round(s)) > 1e-6 || s < 0) {
      throw DataError(
          source + ": pose " + std::to_string(i + 1) + " has stamp " + num(s, "%.9g") +
          ", which is not a frame index (a whole number >= 0); match by time with a times file instead");
    }
    if (s >= static_cast<double>(gt.size())) {
      throw DataError(source + ": pose " + std::to_string(i + 1) + " is frame " + num(s, "%.0f") +
                      ", but the ground truth has only " + std::to_string(gt.size()) + " frames (0.." +
                      std::to_string(gt.size() - 1) + ")");
    }
    frame_of.push_back(static_cast<int>(std::lround(s)));
  }
  MatchedPoses m = assemble(gt, est, std::move(frame_of), source);
  m.rule = kitti ? "by frame index (KITTI line = frame)" : "by frame index (TUM stamp = frame)";
  return m;
}

MatchedPoses matchByTime(const std::vector<Pose3>& gt, const std::vector<double>& gt_times,
                         const EstimateFile& est, const TimeMatchOptions& options,
                         const std::string& source) {
  if (est.format != TrajectoryFormat::tum)
    throw DataError(source + ": KITTI files carry no time stamps; they are matched by frame index");
  if (gt_times.size() != gt.size()) {
    throw DataError("the times file has " + std::to_string(gt_times.size()) + " stamps for " +
                    std::to_string(gt.size()) + " ground-truth poses");
  }
  if (!std::is_sorted(gt_times.begin(), gt_times.end()))
    throw DataError("the ground-truth times are not in increasing order");
  std::vector<int> frame_of;
  for (size_t i = 0; i < est.poses.size(); ++i) {
    const double t = est.poses[i].stamp_s - options.stamp_offset_s;
    auto it = std::lower_bound(gt_times.begin(), gt_times.end(), t);
    size_t k = static_cast<size_t>(it - gt_times.begin());
    if (k == gt_times.size() || (k > 0 && t - gt_times[k - 1] < gt_times[k] - t)) --k;
    const double dt = std::abs(gt_times[k] - t);
    if (dt > options.tolerance_s) {
      throw DataError(
          source + ": pose " + std::to_string(i + 1) + " (stamp " + num(est.poses[i].stamp_s, "%.6f") +
          (options.stamp_offset_s != 0 ? " - offset " + num(options.stamp_offset_s) : std::string()) +
          ") is " + num(dt, "%.4f") + " s from the nearest ground-truth time (frame " + std::to_string(k) +
          ", " + num(gt_times[k], "%.6f") + " s); the tolerance is " + num(options.tolerance_s) + " s");
    }
    frame_of.push_back(static_cast<int>(k));
  }
  MatchedPoses m = assemble(gt, est, std::move(frame_of), source);
  m.rule =
      "by time stamp (within " + num(options.tolerance_s * 1e3) + " ms" +
      (options.stamp_offset_s != 0 ? ", stamps - " + num(options.stamp_offset_s) + " s" : std::string()) +
      ")";
  return m;
}

Pose3 alignUmeyama(const std::vector<Eigen::Vector3d>& est, const std::vector<Eigen::Vector3d>& gt) {
  if (est.size() != gt.size()) {
    throw DataError("alignment needs as many estimated positions (" + std::to_string(est.size()) +
                    ") as ground-truth positions (" + std::to_string(gt.size()) + ")");
  }
  if (est.size() < 3)
    throw DataError("alignment needs at least 3 positions, got " + std::to_string(est.size()));
  const double n = static_cast<double>(est.size());
  Eigen::Vector3d mu_e = Eigen::Vector3d::Zero(), mu_g = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < est.size(); ++i) {
    mu_e += est[i];
    mu_g += gt[i];
  }
  mu_e /= n;
  mu_g /= n;
  // Cross-covariance of the centred point sets; the rotation is U S V^T of its SVD, with S flipping the
  // last axis when U V^T would be a reflection.
  Eigen::Matrix3d sigma = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < est.size(); ++i) sigma += (gt[i] - mu_g) * (est[i] - mu_e).transpose();
  sigma /= n;
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(sigma, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) S(2, 2) = -1;
  Pose3 T = Pose3::Identity();
  T.linear() = svd.matrixU() * S * svd.matrixV().transpose();
  T.translation() = mu_g - T.linear() * mu_e;
  return T;
}

RelativeErrors kittiRelativeErrors(const MatchedPoses& m, const RelativeErrorOptions& options) {
  RelativeErrors r;
  r.t_rel_pct = r.r_rel_deg_per_100m = std::numeric_limits<double>::quiet_NaN();
  const size_t n = m.gt.size();
  std::vector<double> dist(n, 0.0);
  for (size_t i = 1; i < n; ++i)
    dist[i] = dist[i - 1] + (m.gt[i].translation() - m.gt[i - 1].translation()).norm();
  r.path_length_m = n ? dist.back() : 0.0;
  if (options.lengths_m.empty() || options.step_frames < 1) {
    r.reason = "no segment lengths";
    return r;
  }
  const int step = options.step_frames;
  double t_sum = 0, r_sum = 0;
  int next_start = 0;
  for (size_t i = 0; i < n; ++i) {
    if (m.frames[i] < next_start) continue;
    next_start = (m.frames[i] / step + 1) * step;
    for (double len : options.lengths_m) {
      const auto it = std::lower_bound(dist.begin() + static_cast<long>(i), dist.end(), dist[i] + len);
      if (it == dist.end()) continue;
      const size_t j = static_cast<size_t>(it - dist.begin());
      const Pose3 E = (m.gt[i].inverse() * m.gt[j]).inverse() * (m.est[i].inverse() * m.est[j]);
      // The devkit's rotationError: the angle from the trace, clamped into acos' domain.
      const double c = 0.5 * (E.linear().trace() - 1.0);
      t_sum += E.translation().norm() / len;
      r_sum += std::acos(std::max(std::min(c, 1.0), -1.0)) / len;
      ++r.segments;
    }
  }
  if (r.segments == 0) {
    r.reason = "the matched ground truth travels " + num(r.path_length_m, "%.1f") +
               " m, less than the shortest segment (" +
               num(*std::min_element(options.lengths_m.begin(), options.lengths_m.end())) + " m)";
    return r;
  }
  r.valid = true;
  r.t_rel_pct = 100.0 * t_sum / r.segments;
  r.r_rel_deg_per_100m = r_sum / r.segments * 180.0 / M_PI * 100.0;
  return r;
}

TrajectoryMetrics evaluateTrajectory(const MatchedPoses& m, const RelativeErrorOptions& options) {
  if (m.gt.size() != m.est.size() || m.frames.size() != m.gt.size()) {
    throw DataError("matched poses: " + std::to_string(m.gt.size()) + " ground truth, " +
                    std::to_string(m.est.size()) + " estimated, " + std::to_string(m.frames.size()) +
                    " frames");
  }
  if (m.gt.size() < 3) {
    throw DataError("only " + std::to_string(m.gt.size()) +
                    " poses matched the ground truth; at least 3 are needed");
  }
  std::vector<Eigen::Vector3d> p_est, p_gt;
  for (size_t i = 0; i < m.gt.size(); ++i) {
    if (!finitePose(m.gt[i]) || !finitePose(m.est[i])) {
      throw DataError(std::string(finitePose(m.gt[i]) ? "the estimated" : "the ground-truth") +
                      " pose of frame " + std::to_string(m.frames[i]) + " is not finite");
    }
    p_est.emplace_back(m.est[i].translation());
    p_gt.emplace_back(m.gt[i].translation());
  }
  TrajectoryMetrics t;
  t.T_gt_est = alignUmeyama(p_est, p_gt);
  double sq = 0;
  for (size_t i = 0; i < p_est.size(); ++i) sq += (p_gt[i] - t.T_gt_est * p_est[i]).squaredNorm();
  t.ate_rmse_m = std::sqrt(sq / static_cast<double>(p_est.size()));
  t.relative = kittiRelativeErrors(m, options);
  return t;
}

}  // namespace binloop
