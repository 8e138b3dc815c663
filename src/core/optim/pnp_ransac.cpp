#include "binloop/optim/pnp_ransac.h"

#include <opencv2/calib3d.hpp>
#include <stdexcept>

#include "binloop/util/hash_random.h"

namespace binloop {

namespace {

bool solve(const std::vector<cv::Point3d>& P, const std::vector<cv::Point2d>& p, const cv::Mat& K, int flags,
           bool guess, cv::Mat* rvec, cv::Mat* tvec) {
  try {
    return cv::solvePnP(P, p, K, cv::noArray(), *rvec, *tvec, guess, flags);
  } catch (const cv::Exception&) {  // degenerate sample (e.g. collinear points)
    return false;
  }
}

Pose3 toPose(const cv::Mat& rvec, const cv::Mat& tvec) {
  cv::Mat R;
  cv::Rodrigues(rvec, R);
  Pose3 T = Pose3::Identity();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) T.linear()(i, j) = R.at<double>(i, j);
    T.translation()(i) = tvec.at<double>(i);
  }
  return orthonormalized(T);
}

}  // namespace

PnpRansacResult solvePnpRansac(const std::vector<Eigen::Vector3d>& p_w,
                               const std::vector<Eigen::Vector2d>& uv, const std::vector<double>& inv_sigma2,
                               const StereoCamera& cam, const PnpRansacParams& params, uint64_t seed) {
  if (p_w.size() != uv.size() || (!inv_sigma2.empty() && inv_sigma2.size() != uv.size())) {
    throw std::invalid_argument("solvePnpRansac: " + std::to_string(p_w.size()) + " points, " +
                                std::to_string(uv.size()) + " pixels, " + std::to_string(inv_sigma2.size()) +
                                " weights");
  }
  PnpRansacResult best;
  const int n = static_cast<int>(p_w.size());
  if (n < 4 || n < params.min_inliers) return best;
  const cv::Mat K = (cv::Mat_<double>(3, 3) << cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1);
  auto classify = [&](const Pose3& T, std::vector<uint8_t>* in) {
    int count = 0;
    in->assign(n, 0);
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d c = T * p_w[i];
      if (c.z() <= 0) continue;
      const Eigen::Vector2d d = cam.project(c) - uv[i];
      const double du = d.x(), dv = d.y();
      const double w = inv_sigma2.empty() ? 1.0 : inv_sigma2[i];
      if ((du * du + dv * dv) * w <= params.chi2) (*in)[i] = 1, ++count;
    }
    return count;
  };
  HashRng rng(seed);
  std::vector<cv::Point3d> P(4);
  std::vector<cv::Point2d> p(4);
  std::vector<uint8_t> in;
  for (int it = 0; it < params.iterations; ++it) {
    int idx[4];
    for (int k = 0; k < 4; ++k) {
      bool again;
      do {
        idx[k] = rng.below(n);
        again = false;
        for (int j = 0; j < k; ++j) again |= idx[j] == idx[k];
      } while (again);
      P[k] = {p_w[idx[k]].x(), p_w[idx[k]].y(), p_w[idx[k]].z()};
      p[k] = {uv[idx[k]].x(), uv[idx[k]].y()};
    }
    cv::Mat rvec, tvec;
    if (!solve(P, p, K, cv::SOLVEPNP_AP3P, false, &rvec, &tvec)) continue;
    const Pose3 T = toPose(rvec, tvec);
    const int count = classify(T, &in);
    best.iterations = it + 1;
    if (count > best.inliers) {
      best.inliers = count;
      best.T_c_w = T;
      best.inlier = in;
      if (count >= params.stop_ratio * n) break;
    }
  }
  if (best.inliers < params.min_inliers) return best;
  // Refine on the inliers (iterative, from the sample's pose), then classify again.
  std::vector<cv::Point3d> Pi;
  std::vector<cv::Point2d> pi;
  for (int i = 0; i < n; ++i) {
    if (best.inlier[i]) {
      Pi.emplace_back(p_w[i].x(), p_w[i].y(), p_w[i].z());
      pi.emplace_back(uv[i].x(), uv[i].y());
    }
  }
  cv::Mat R(3, 3, CV_64F), rvec, tvec(3, 1, CV_64F);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) R.at<double>(i, j) = best.T_c_w.linear()(i, j);
    tvec.at<double>(i) = best.T_c_w.translation()(i);
  }
  cv::Rodrigues(R, rvec);
  if (solve(Pi, pi, K, cv::SOLVEPNP_ITERATIVE, true, &rvec, &tvec)) {
    const Pose3 T = toPose(rvec, tvec);
    const int count = classify(T, &in);
    if (count >= best.inliers) {
      best.T_c_w = T;
      best.inliers = count;
      best.inlier = in;
    }
  }
  best.ok = best.inliers >= params.min_inliers;
  return best;
}

}  // namespace binloop
