#include "binloop/optim/reprojection_costs.h"

namespace binloop {

Pose3 poseFromIncrement(const double* xi, const Pose3& T0_c_w) {
  // Column-major, as Eigen stores it. Below |w|^2 = machine epsilon Ceres uses R = I + [w]x, the same
  // first-order rule as AngleAxisRotatePoint in the residuals; at w = 0 it is exactly I.
  Eigen::Matrix3d dR;
  ceres::AngleAxisToRotationMatrix(xi, dR.data());
  const Eigen::Vector3d rho(xi[3], xi[4], xi[5]);
  Pose3 T = Pose3::Identity();
  T.linear() = dR * T0_c_w.linear();
  T.translation() = dR * T0_c_w.translation() + rho;
  return T;
}

}  // namespace binloop
