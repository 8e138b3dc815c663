#include "binloop/io/trajectory_io.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>

#include "binloop/io/data_error.h"
#include "binloop/io/number_lines.h"

namespace binloop {

namespace {

// A rotation read from text is only trusted after this check; the tolerance admits KITTI's 7 digits.
void requireRotation(const std::string& path, int line, const Eigen::Matrix3d& R) {
  const double orth = (R * R.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (orth > 1e-3 || std::abs(R.determinant() - 1.0) > 1e-3)
    throw dataError(path, line, "the 3x3 part is not a rotation matrix");
}

struct File {
  explicit File(const std::string& path) : path(path), f(std::fopen(path.c_str(), "w")) {
    if (!f) throw dataError(path, 0, "cannot be opened for writing");
  }
  ~File() {
    if (f) std::fclose(f);
  }
  void close() {
    const bool ok = std::fclose(f) == 0;
    f = nullptr;
    if (!ok) throw dataError(path, 0, "write failed");
  }
  std::string path;
  FILE* f;
};

}  // namespace

std::vector<Pose3> readKittiPoses(const std::string& path) {
  std::vector<Pose3> poses;
  for (const auto& l : readNumberLines(path)) {
    requireCount(path, l, 12, "a KITTI pose (3x4 matrix, row-major)");
    Eigen::Matrix<double, 3, 4, Eigen::RowMajor> M(l.values.data());
    requireRotation(path, l.line_no, M.leftCols<3>());
    Pose3 T = Pose3::Identity();
    // Re-orthonormalise: 7-digit text rounding leaves R slightly off SO(3).
    T.linear() = Eigen::Quaterniond(Eigen::Matrix3d(M.leftCols<3>())).normalized().toRotationMatrix();
    T.translation() = M.col(3);
    poses.push_back(T);
  }
  return poses;
}

void writeKittiPoses(const std::string& path, const std::vector<Pose3>& poses) {
  File out(path);
  for (const auto& T : poses) {
    const auto& M = T.matrix();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) std::fprintf(out.f, (r == 0 && c == 0) ? "%.9e" : " %.9e", M(r, c));
    std::fprintf(out.f, "\n");
  }
  out.close();
}

Trajectory readTumTrajectory(const std::string& path) {
  Trajectory traj;
  for (const auto& l : readNumberLines(path)) {
    requireCount(path, l, 8, "a TUM pose (stamp tx ty tz qx qy qz qw)");
    const auto& v = l.values;
    Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    if (std::abs(q.norm() - 1.0) > 1e-3) throw dataError(path, l.line_no, "quaternion is not unit length");
    StampedPose p;
    p.stamp_s = v[0];
    p.T_w_c = Pose3::Identity();
    p.T_w_c.linear() = q.normalized().toRotationMatrix();
    p.T_w_c.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
    traj.push_back(p);
  }
  return traj;
}

void writeTumTrajectory(const std::string& path, const Trajectory& traj) {
  File out(path);
  for (const auto& p : traj) {
    const Eigen::Quaterniond q(p.T_w_c.rotation());
    const Eigen::Vector3d t = p.T_w_c.translation();
    std::fprintf(out.f, "%.9f %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", p.stamp_s, t.x(), t.y(), t.z(), q.x(),
                 q.y(), q.z(), q.w());
  }
  out.close();
}

std::vector<double> readTimes(const std::string& path) {
  std::vector<double> times;
  for (const auto& l : readNumberLines(path)) {
    requireCount(path, l, 1, "a time stamp");
    if (!times.empty() && l.values[0] < times.back()) throw dataError(path, l.line_no, "time goes backwards");
    times.push_back(l.values[0]);
  }
  return times;
}

void writeTimes(const std::string& path, const std::vector<double>& times) {
  File out(path);
  for (double t : times) std::fprintf(out.f, "%.6e\n", t);
  out.close();
}

std::vector<std::pair<int, int>> readIndexPairs(const std::string& path) {
  std::vector<std::pair<int, int>> pairs;
  for (const auto& l : readNumberLines(path)) {
    requireCount(path, l, 2, "a pair 'query ref'");
    const double a = l.values[0], b = l.values[1];
    if (a < 0 || b < 0 || a != std::floor(a) || b != std::floor(b))
      throw dataError(path, l.line_no, "indices must be whole numbers >= 0");
    pairs.emplace_back(static_cast<int>(a), static_cast<int>(b));
  }
  return pairs;
}

}  // namespace binloop
