#include "binloop/optim/rigid_alignment.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "binloop/util/hash_random.h"

namespace binloop {

std::optional<Pose3> hornAlignment(const std::vector<Eigen::Vector3d>& a,
                                   const std::vector<Eigen::Vector3d>& b) {
  const size_t n = a.size();
  if (n < 3 || b.size() != n) return std::nullopt;
  Eigen::Vector3d ca = Eigen::Vector3d::Zero(), cb = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < n; ++i) ca += a[i], cb += b[i];
  ca /= static_cast<double>(n);
  cb /= static_cast<double>(n);
  Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < n; ++i) M += (b[i] - cb) * (a[i] - ca).transpose();
  // Collinear (or coincident) points: the second singular value of M vanishes.
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(M);
  if (svd.singularValues()(1) <= 1e-9 * std::max(1.0, svd.singularValues()(0))) return std::nullopt;
  Eigen::Matrix4d N;
  const double Sxx = M(0, 0), Sxy = M(0, 1), Sxz = M(0, 2), Syx = M(1, 0), Syy = M(1, 1), Syz = M(1, 2),
               Szx = M(2, 0), Szy = M(2, 1), Szz = M(2, 2);
  N << Sxx + Syy + Szz, Syz - Szy, Szx - Sxz, Sxy - Syx,  //
      Syz - Szy, Sxx - Syy - Szz, Sxy + Syx, Szx + Sxz,   //
      Szx - Sxz, Sxy + Syx, -Sxx + Syy - Szz, Syz + Szy,  //
      Sxy - Syx, Szx + Sxz, Syz + Szy, -Sxx - Syy + Szz;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> es(N);
  const Eigen::Vector4d q = es.eigenvectors().col(3);  // eigenvalues ascending
  Pose3 T = Pose3::Identity();
  T.linear() = Eigen::Quaterniond(q(0), q(1), q(2), q(3)).normalized().toRotationMatrix();
  T.translation() = ca - T.linear() * cb;
  return T;
}

RigidRansacResult rigidRansac(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b,
                              const RigidRansacParams& p, uint64_t seed) {
  RigidRansacResult best;
  const size_t n = a.size();
  best.inlier.assign(n, 0);
  if (n < 3 || b.size() != n) return best;
  HashRng rng(seed);
  auto classify = [&](const Pose3& T, std::vector<uint8_t>* in) {
    int count = 0;
    for (size_t i = 0; i < n; ++i) {
      const double th = p.absolute_m + p.relative * a[i].norm();
      (*in)[i] = (a[i] - T * b[i]).squaredNorm() < th * th;
      count += (*in)[i];
    }
    return count;
  };
  std::vector<uint8_t> in(n);
  int needed = p.iterations;
  for (int it = 0; it < std::min(p.iterations, needed); ++it) {
    best.iterations = it + 1;
    const int i = rng.below(static_cast<int>(n));
    int j = rng.below(static_cast<int>(n)), k = rng.below(static_cast<int>(n));
    if (i == j || j == k || i == k) continue;
    const auto T = hornAlignment({a[i], a[j], a[k]}, {b[i], b[j], b[k]});
    if (!T) continue;
    const int c = classify(*T, &in);
    if (c > best.inliers) {
      best.inliers = c;
      best.inlier = in;
      best.T_a_b = *T;
      const double w = static_cast<double>(c) / static_cast<double>(n), miss = 1 - w * w * w;
      if (p.confidence > 0 && p.confidence < 1 && miss < 1)
        needed = miss <= 0 ? 0 : static_cast<int>(std::ceil(std::log(1 - p.confidence) / std::log(miss)));
    }
  }
  if (best.inliers < std::max(3, p.min_inliers)) {
    best.ok = false;
    return best;
  }
  // Refit on every inlier, then classify once more with the refit.
  std::vector<Eigen::Vector3d> ai, bi;
  for (size_t i = 0; i < n; ++i)
    if (best.inlier[i]) ai.push_back(a[i]), bi.push_back(b[i]);
  if (const auto T = hornAlignment(ai, bi)) {
    best.T_a_b = *T;
    best.inliers = classify(*T, &best.inlier);
  }
  best.ok = best.inliers >= p.min_inliers;
  return best;
}

}  // namespace binloop
