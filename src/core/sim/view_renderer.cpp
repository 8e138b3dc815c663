#include "binloop/sim/view_renderer.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace binloop::sim {

namespace {

constexpr float kGroundTexelsPerM = 64.0f;

// The texture and a second copy of it turned by 37 degrees and scaled by 1/sqrt(2), blended with the
// contrast kept: the two periods are incommensurate, so the sum does not repeat where either layer does.
float aperiodicSample(const Texture& tex, float u, float v, int level) {
  constexpr float kC = 0.7986355f * 0.70710678f, kS = 0.6018150f * 0.70710678f;  // cos, sin 37 deg / sqrt 2
  const float a = tex.sample(u, v, level);
  const float b = tex.sample(kC * u - kS * v + 131.0f, kS * u + kC * v + 57.0f, level);
  return std::clamp(tex.mean() + (a + b - 2 * tex.mean()) * 0.70710678f, 0.0f, 255.0f);
}

// Mip level for a surface seen with `texels_per_px` texels under one pixel: log2, rounded, >= 0.
inline int mipLevel(float texels_per_px) {
  if (texels_per_px <= 1.41f) return 0;
  int e;
  std::frexp(texels_per_px * 0.7071f, &e);
  return e - 1;
}

// Crown-and-trunk cut-out on a tree billboard (u across, v up, metres); `noise` in [0, 1] roughens the crown.
inline bool treeOpaque(float u, float v, float lu, float lv, float noise) {
  const float du = (u - lu * 0.5f) / (lu * 0.5f), dv = (v - lv * 0.62f) / (lv * 0.38f);
  if (du * du + dv * dv < 1.0f - 0.45f * noise) return true;
  return std::abs(u - lu * 0.5f) < 0.15f && v < lv * 0.35f;
}

// Where the ray c + t * ray (world frame, unit camera z) meets the rigid ground y = H(x, z): Newton's method
// on f(t) = H(x(t), z(t)) - y(t), from `t0` (the per-frame plane's hit, a close guess). False when it meets
// no ground in front (the ray rises faster than the ground) or does not settle. `n_dot_ray`: the surface's
// unit normal (pointing down) dotted with `ray`.
bool hitGround(const World& world, const Eigen::Vector3d& c, const Eigen::Vector3d& ray, double t0, double* t,
               double* n_dot_ray) {
  double tt = t0;
  for (int it = 0; it < 12; ++it) {
    const Eigen::Vector3d p = c + tt * ray;
    double hx, hz;
    const double f = world.groundY(p.x(), p.z(), &hx, &hz) - p.y();
    const double df = hx * ray.x() + hz * ray.z() - ray.y();  // negative while the ray descends onto it
    if (df >= -1e-9) return false;
    if (std::abs(f) < 1e-4) {
      *t = tt;
      *n_dot_ray = -df / std::sqrt(1 + hx * hx + hz * hz);
      return tt > 0;
    }
    tt -= f / df;
    if (!(tt > 0) || tt > 1e4) return false;
  }
  return false;
}

}  // namespace

void ViewRenderer::render(const World& world, const StereoCamera& cam, const Pose3& T_w_c, cv::Mat* gray,
                          cv::Mat* depth) {
  gray->create(cam.height, cam.width, CV_32F);
  depth->create(cam.height, cam.width, CV_32F);
  depth->setTo(std::numeric_limits<float>::infinity());
  // Sky: a smooth gradient, featureless as a real overcast sky.
  for (int y = 0; y < cam.height; ++y) gray->row(y).setTo(215.0f - 30.0f * y / cam.height);
  drawGround(world, cam, T_w_c, *gray, *depth);
  const Eigen::Vector3d c = T_w_c.translation();
  world.quadsNear(c.x(), c.z(), max_distance_, &candidates_);
  for (int k : candidates_) drawQuad(world, world.quads()[k], cam, T_w_c, *gray, *depth);
}

void ViewRenderer::drawGround(const World& world, const StereoCamera& cam, const Pose3& T_w_c, cv::Mat& gray,
                              cv::Mat& depth) {
  Eigen::Vector3d n;
  double d;
  world.groundPlane(T_w_c, &n, &d);
  const Eigen::Matrix3d R = T_w_c.rotation();
  const Eigen::Vector3d c = T_w_c.translation();
  const double h = d - n.dot(c);  // signed distance of the plane below the camera
  const Eigen::Vector3d dx = R.col(0) / cam.fx;
  const double n_dx = n.dot(dx);
  const auto& bank = world.bank();
  const bool aperiodic = world.params().aperiodic_ground;
  const bool rigid = world.rigidGround();
  for (int y = 0; y < cam.height; ++y) {
    const Eigen::Vector3d row0 = R * Eigen::Vector3d(-cam.cx / cam.fx, (y - cam.cy) / cam.fy, 1.0);
    const double n_row0 = n.dot(row0);
    float* g = gray.ptr<float>(y);
    float* z = depth.ptr<float>(y);
    for (int x = 0; x < cam.width; ++x) {
      const double denom = n_row0 + x * n_dx;
      if (!rigid && denom <= 1e-6) continue;  // above the plane: sky
      const Eigen::Vector3d ray = row0 + x * dx;
      // Camera-z depth (the ray has unit z) and the surface normal dotted with the ray: the plane's, which is
      // also where the rigid ground's search starts.
      double t = denom > 1e-6 ? h / denom : max_distance_, n_dot_ray = denom;
      if (rigid && !hitGround(world, c, ray, t, &t, &n_dot_ray)) continue;
      if (t <= near_ || t > max_distance_) continue;
      const double ray_len = ray.norm();
      const double cosang = n_dot_ray / ray_len;
      const Eigen::Vector3d p = c + t * ray;
      const double range = t * ray_len;
      const int level =
          mipLevel(static_cast<float>(range * kGroundTexelsPerM / (cam.fx * std::sqrt(cosang))));
      const Texture& tex = bank.textures[world.groundMaterial(p.x(), p.z())];
      const float u = static_cast<float>(p.x() * kGroundTexelsPerM),
                  v = static_cast<float>(p.z() * kGroundTexelsPerM);
      g[x] = aperiodic ? aperiodicSample(tex, u, v, level) : tex.sample(u, v, level);
      z[x] = static_cast<float>(t);
    }
  }
}

namespace {

// The span [left, right] of a convex polygon on image row y: between its extreme edge crossings.
std::pair<float, float> rowSpan(const Eigen::Vector2f* poly, int np, int y) {
  float xl = 1e9f, xr = -1e9f;
  for (int i = 0; i < np; ++i) {
    const Eigen::Vector2f& p = poly[i];
    const Eigen::Vector2f& r = poly[(i + 1) % np];
    if ((p.y() <= y && r.y() >= y) || (r.y() <= y && p.y() >= y)) {
      const float x = std::abs(r.y() - p.y()) < 1e-6f
                          ? std::min(p.x(), r.x())
                          : p.x() + (y - p.y()) * (r.x() - p.x()) / (r.y() - p.y());
      const float x2 = std::abs(r.y() - p.y()) < 1e-6f ? std::max(p.x(), r.x()) : x;
      xl = std::min(xl, x);
      xr = std::max(xr, x2);
    }
  }
  return {xl, xr};
}

}  // namespace

void ViewRenderer::drawQuad(const World& world, const Quad& q, const StereoCamera& cam, const Pose3& T_w_c,
                            cv::Mat& gray, cv::Mat& depth) {
  const Eigen::Matrix3f R_cw = T_w_c.rotation().transpose().cast<float>();
  const Eigen::Vector3f c = T_w_c.translation().cast<float>();
  const Eigen::Vector3f centre = q.o + q.a * (q.lu / 2) + q.b * (q.lv / 2);
  const float half = 0.5f * std::hypot(q.lu, q.lv);
  const float dist = (centre - c).norm();
  if (dist - half > q.max_distance || dist - half > max_distance_) return;

  // Quad in camera coordinates: X_c = A u + B v + C.
  const Eigen::Vector3f A = R_cw * q.a, B = R_cw * q.b, C = R_cw * (q.o - c);
  Eigen::Vector3f corners[4] = {C, C + A * q.lu, C + A * q.lu + B * q.lv, C + B * q.lv};
  // Clip against the near plane (Sutherland–Hodgman), then project.
  Eigen::Vector2f poly[8];
  int np = 0;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector3f& p = corners[i];
    const Eigen::Vector3f& r = corners[(i + 1) % 4];
    const bool pin = p.z() >= near_, rin = r.z() >= near_;
    auto project = [&](const Eigen::Vector3f& v) {
      return Eigen::Vector2f(cam.fx * v.x() / v.z() + cam.cx, cam.fy * v.y() / v.z() + cam.cy);
    };
    if (pin) poly[np++] = project(p);
    if (pin != rin) {
      const float t = (near_ - p.z()) / (r.z() - p.z());
      poly[np++] = project(p + t * (r - p));
    }
  }
  if (np < 3) return;
  float ymin = 1e9f, ymax = -1e9f, xmin = 1e9f, xmax = -1e9f;
  for (int i = 0; i < np; ++i) {
    ymin = std::min(ymin, poly[i].y());
    ymax = std::max(ymax, poly[i].y());
    xmin = std::min(xmin, poly[i].x());
    xmax = std::max(xmax, poly[i].x());
  }
  if (xmax < 0 || xmin > cam.width - 1 || ymax < 0 || ymin > cam.height - 1) return;

  // Pixel -> (u, v): the inverse of the plane's homography H = K [A B C].
  Eigen::Matrix3f K;
  K << static_cast<float>(cam.fx), 0, static_cast<float>(cam.cx), 0, static_cast<float>(cam.fy),
      static_cast<float>(cam.cy), 0, 0, 1;
  Eigen::Matrix3f M;
  M << A, B, C;
  const Eigen::Matrix3f H = K * M;
  if (std::abs(H.determinant()) < 1e-12f) return;  // seen edge-on
  const Eigen::Matrix3f Hinv = H.inverse();
  const Eigen::Vector3f step = Hinv.col(0);

  const Texture& tex = world.bank().textures[q.texture];
  const Eigen::Vector3f n_c = A.cross(B);
  const float cosang = std::max(0.05f, std::abs(n_c.dot((R_cw * (centre - c)).normalized())));
  const float level_scale = q.texels_per_m / (static_cast<float>(cam.fx) * std::sqrt(cosang));

  const int y0 = std::max(0, static_cast<int>(std::ceil(ymin))),
            y1 = std::min(cam.height - 1, static_cast<int>(std::floor(ymax)));
  for (int y = y0; y <= y1; ++y) {
    const auto [xl, xr] = rowSpan(poly, np, y);
    const int xa = std::max(0, static_cast<int>(std::ceil(xl))),
              xb = std::min(cam.width - 1, static_cast<int>(std::floor(xr)));
    if (xa > xb) continue;
    float* g = gray.ptr<float>(y);
    float* z = depth.ptr<float>(y);
    Eigen::Vector3f h = Hinv * Eigen::Vector3f(static_cast<float>(xa), static_cast<float>(y), 1.0f);
    for (int x = xa; x <= xb; ++x, h += step) {
      const float iw = 1.0f / h.z();
      const float u = std::clamp(h.x() * iw, 0.0f, q.lu), v = std::clamp(h.y() * iw, 0.0f, q.lv);
      const float zc = A.z() * u + B.z() * v + C.z();
      if (zc >= z[x] || zc < near_) continue;
      const float tu = q.off_u + u * q.texels_per_m, tv = q.off_v + (q.lv - v) * q.texels_per_m;
      if (q.shape == Quad::kTree &&
          !treeOpaque(u, v, q.lu, q.lv, tex.sample(tu * 0.25f, tv * 0.25f, 3) / 255.0f))
        continue;
      g[x] = q.shade * tex.sample(tu, tv, mipLevel(zc * level_scale));
      z[x] = zc;
    }
  }
}

}  // namespace binloop::sim
