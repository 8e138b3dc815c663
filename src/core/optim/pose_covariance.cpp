#include "binloop/optim/pose_covariance.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <cmath>

namespace binloop {

PoseCovariance poseCovariance(const StereoCamera& cam, const Pose3& T_w_c,
                              const std::vector<PoseObservation>& inliers) {
  PoseCovariance out;
  const Eigen::Matrix3d R_cw = T_w_c.linear().transpose();
  const Eigen::Vector3d c = T_w_c.translation();
  Matrix6d H = Matrix6d::Zero();
  double chi2 = 0;
  int rows = 0;
  for (const PoseObservation& o : inliers) {
    // p_c = R_cw exp(-dtheta) (p_w - c - dc): d p_c / d dc = -R_cw, d p_c / d dtheta = R_cw [p_w - c]x.
    const Eigen::Vector3d q = o.p_w - c;
    const Eigen::Vector3d p = R_cw * q;
    if (p.z() <= 0) continue;
    Eigen::Matrix<double, 3, 6> dp;
    dp.leftCols<3>() = -R_cw;
    dp.rightCols<3>() = R_cw * skew(q);
    const double iz = 1 / p.z(), iz2 = iz * iz;
    const bool stereo = o.u_right >= 0;
    Eigen::Matrix<double, 3, 3> dproj;               // (u, v, u_right) by p_c
    dproj << cam.fx * iz, 0, -cam.fx * p.x() * iz2,  //
        0, cam.fy * iz, -cam.fy * p.y() * iz2,       //
        cam.fx * iz, 0, (cam.bf() - cam.fx * p.x()) * iz2;
    const Eigen::Matrix<double, 3, 6> J = dproj * dp;
    const Eigen::Vector2d uv = cam.project(p);
    double r2 = (uv - o.uv).squaredNorm();
    if (stereo) {
      H += o.inv_sigma2 * J.transpose() * J;
      r2 += std::pow(uv.x() - cam.bf() * iz - o.u_right, 2);
    } else {
      H += o.inv_sigma2 * J.topRows<2>().transpose() * J.topRows<2>();
    }
    chi2 += o.inv_sigma2 * r2;
    rows += stereo ? 3 : 2;
    ++out.observations;
  }
  if (out.observations < 3 || rows <= 6) return out;
  const Eigen::LDLT<Matrix6d> ldlt(H);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive() ||
      ldlt.vectorD().minCoeff() <= 1e-12 * ldlt.vectorD().maxCoeff())
    return out;
  const double variance = chi2 / (rows - 6);
  out.sigma_px = std::sqrt(variance);
  out.covariance = variance * ldlt.solve(Matrix6d::Identity());
  out.covariance = 0.5 * (out.covariance + out.covariance.transpose()).eval();
  out.valid = out.covariance.allFinite();
  return out;
}

}  // namespace binloop
