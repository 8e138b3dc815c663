#include "binloop/map/point_projection.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace binloop {

bool projectIntoFrame(const msg::MapPoint& mp, const Pose3& T_c_w, const StereoCamera& cam,
                      const ScalePyramid& s, ProjectedPoint* out) {
  const Eigen::Vector3d p_c = T_c_w * mp.p_w;
  if (p_c.z() <= 0) return false;
  const double inv_z = 1.0 / p_c.z();
  const double u = cam.fx * p_c.x() * inv_z + cam.cx;
  const double v = cam.fy * p_c.y() * inv_z + cam.cy;
  if (u < 0 || u >= cam.width || v < 0 || v >= cam.height) return false;
  const Eigen::Vector3d o_w = T_c_w.inverse().translation();
  const Eigen::Vector3d ray = mp.p_w - o_w;
  const double dist = ray.norm();
  if (mp.max_distance > 0 && (dist < 0.8 * mp.min_distance || dist > 1.2 * mp.max_distance)) return false;
  double view_cos = 1;
  if (mp.normal.squaredNorm() > 0) {
    view_cos = ray.dot(mp.normal.cast<double>()) / dist;
    if (view_cos < 0.5) return false;
  }
  out->point = &mp;
  out->u = static_cast<float>(u);
  out->v = static_cast<float>(v);
  out->u_right = static_cast<float>(u - cam.bf() * inv_z);
  out->level = mp.max_distance > 0 ? s.predictLevel(mp.max_distance, static_cast<float>(dist)) : 0;
  out->view_cos = static_cast<float>(view_cos);
  return true;
}

std::vector<uint8_t> rotationConsistent(const std::vector<float>& angle_diff_deg) {
  constexpr int kBins = 30;
  std::array<int, kBins> count{};
  std::vector<int> bin(angle_diff_deg.size());
  for (size_t i = 0; i < angle_diff_deg.size(); ++i) {
    float a = std::isfinite(angle_diff_deg[i]) ? std::fmod(angle_diff_deg[i], 360.f) : 0.f;
    if (a < 0) a += 360.f;
    bin[i] = std::min(kBins - 1, static_cast<int>(a * kBins / 360.f));
    ++count[bin[i]];
  }
  std::array<int, kBins> order;
  for (int b = 0; b < kBins; ++b) order[b] = b;
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return count[a] > count[b]; });
  std::array<uint8_t, kBins> keep{};
  for (int k = 0; k < 3; ++k)
    if (count[order[k]] > 0 && count[order[k]] >= 0.1 * count[order[0]]) keep[order[k]] = 1;
  std::vector<uint8_t> out(angle_diff_deg.size());
  for (size_t i = 0; i < out.size(); ++i) out[i] = keep[bin[i]];
  return out;
}

}  // namespace binloop
