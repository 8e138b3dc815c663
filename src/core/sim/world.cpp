#include "binloop/sim/world.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "binloop/util/hash_random.h"

namespace binloop::sim {

namespace {

using Vec2 = Eigen::Vector2d;
constexpr double kStep = 2.0;        // route resampling step (m)
constexpr double kRouteCell = 10.0;  // cell of the route-sample grid (m)

Vec2 xz(const Eigen::Vector3d& p) { return {p.x(), p.z()}; }

double pointSegmentDistance(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / std::max(1e-12, ab.squaredNorm()), 0.0, 1.0);
  return (a + t * ab - p).norm();
}

double cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

double segmentDistance(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  const double d1 = cross2(b - a, c - a), d2 = cross2(b - a, d - a);
  const double d3 = cross2(d - c, a - c), d4 = cross2(d - c, b - c);
  if (((d1 > 0) != (d2 > 0)) && ((d3 > 0) != (d4 > 0))) return 0.0;  // they cross
  return std::min({pointSegmentDistance(a, c, d), pointSegmentDistance(b, c, d),
                   pointSegmentDistance(c, a, b), pointSegmentDistance(d, a, b)});
}

// Everything the builder needs while placing things; discarded after World::build.
struct Builder {
  const WorldParams& prm;
  uint64_t seed;
  const std::vector<Eigen::Vector3d>& pts;  // resampled route
  const std::vector<Eigen::Vector3d>& dirs;
  std::function<int(double, double)> nearest;     // nearest route sample
  std::vector<std::pair<Vec2, Vec2>> footprints;  // façades and walls placed so far (2-D segments)
  std::vector<Quad>* quads;

  double routeDistance(const Vec2& q) const {
    const int i = nearest(q.x(), q.y());
    return i < 0 ? 1e9 : (xz(pts[i]) - q).norm();
  }
  bool clearOfRoute(const Vec2& a, const Vec2& b, double clearance) const {
    const int n = std::max(2, static_cast<int>((b - a).norm() / 1.0) + 1);
    for (int k = 0; k <= n; ++k)
      if (routeDistance(a + (b - a) * (static_cast<double>(k) / n)) < clearance) return false;
    return true;
  }
  bool clearOfBuildings(const Vec2& a, const Vec2& b, double margin) const {
    for (const auto& [c, d] : footprints)
      if (segmentDistance(a, b, c, d) < margin) return false;
    return true;
  }
  Eigen::Vector3d right(int i) const { return Eigen::Vector3d(dirs[i].z(), 0, -dirs[i].x()); }
  double groundY(int i) const { return pts[i].y() + prm.camera_height_m; }

  // A vertical quad from a to b (2-D), from `y_base` (below ground, y down) up `height`.
  Quad wall(const Vec2& a, const Vec2& b, double y_base, double height, int tex, HashRng& rng,
            float tpm) const {
    Quad q;
    q.o = Eigen::Vector3f(a.x(), y_base, a.y());
    const Vec2 ab = b - a;
    q.lu = static_cast<float>(ab.norm());
    q.a = Eigen::Vector3f(ab.x() / ab.norm(), 0, ab.y() / ab.norm());
    q.b = Eigen::Vector3f(0, -1, 0);
    q.lv = static_cast<float>(height);
    q.texture = tex;
    q.texels_per_m = tpm;
    q.off_u = static_cast<float>(rng.uniform(0, 512));
    q.off_v = static_cast<float>(rng.uniform(0, 512));
    const Eigen::Vector3f n = q.a.cross(q.b);
    const Eigen::Vector3f sun = Eigen::Vector3f(0.6f, -0.5f, 0.62f).normalized();
    q.shade = 0.7f + 0.3f * std::abs(n.dot(sun));
    return q;
  }

  // Axis-aligned (in route heading) box: 4 sides and a top.
  void box(const Eigen::Vector3d& base_centre, const Eigen::Vector3d& fwd, double len, double wid, double h,
           int tex, HashRng& rng, float tpm, float max_dist) {
    const Eigen::Vector3d f = fwd.normalized(), r(f.z(), 0, -f.x());
    const Eigen::Vector3d c[4] = {
        base_centre - f * len / 2 - r * wid / 2, base_centre + f * len / 2 - r * wid / 2,
        base_centre + f * len / 2 + r * wid / 2, base_centre - f * len / 2 + r * wid / 2};
    for (int k = 0; k < 4; ++k) {
      Quad q = wall(xz(c[k]), xz(c[(k + 1) % 4]), base_centre.y(), h, tex, rng, tpm);
      q.max_distance = max_dist;
      quads->push_back(q);
    }
    Quad top;
    top.o = (c[0] - Eigen::Vector3d(0, h, 0)).cast<float>();
    top.a = f.cast<float>();
    top.b = r.cast<float>();
    top.lu = static_cast<float>(len);
    top.lv = static_cast<float>(wid);
    top.texture = tex;
    top.texels_per_m = tpm;
    top.shade = 1.0f;
    top.max_distance = max_dist;
    quads->push_back(top);
  }

  void facadesOnSide(int side, const TextureBank& bank) {
    std::vector<Quad> placed_facades;
    std::vector<size_t> placed_at;  // route sample of each placed façade (for repeats)
    size_t i = 0;
    while (i + 2 < pts.size()) {
      HashRng rng(hashCombine(hashCombine(seed, 0xFACADEu + side), i));
      const double setback = rng.uniform(prm.setback_min_m, prm.setback_max_m);
      const double len = rng.uniform(prm.facade_len_min_m, prm.facade_len_max_m);
      const size_t j = std::min(pts.size() - 1, i + static_cast<size_t>(std::ceil(len / kStep)));
      const Vec2 a = xz(pts[i] + side * setback * right(i)), b = xz(pts[j] + side * setback * right(j));
      const double y_base = std::max(groundY(i), groundY(j)) + 1.0;  // 1 m into the ground: no gaps on slopes
      const double height = rng.uniform(prm.height_min_m, prm.height_max_m);
      if ((b - a).norm() < 3.0 || !clearOfRoute(a, b, prm.clearance_m) || !clearOfBuildings(a, b, 1.0)) {
        i += 2;
        continue;
      }
      Quad q =
          wall(a, b, y_base, height + 1.0, bank.facades[rng.below(static_cast<int>(bank.facades.size()))],
               rng, static_cast<float>(512.0 / rng.uniform(6.0, 10.0)));
      if (!placed_facades.empty() && rng.chance(prm.repeat_probability)) {
        // Perceptual aliasing: this front is a copy of one at least 30 samples (60 m) back.
        const size_t k = static_cast<size_t>(rng.below(static_cast<int>(placed_facades.size())));
        if (placed_at[k] + 30 < i) {
          q.texture = placed_facades[k].texture;
          q.texels_per_m = placed_facades[k].texels_per_m;
          q.off_u = placed_facades[k].off_u;
          q.off_v = placed_facades[k].off_v;
        }
      }
      quads->push_back(q);
      placed_facades.push_back(q);
      placed_at.push_back(i);
      footprints.emplace_back(a, b);
      // Side walls going back from the street, seen through gaps.
      const double depth = rng.uniform(6.0, 12.0);
      const Eigen::Vector3d away = side * right(i);
      for (const Vec2& p : {a, b}) {
        const Vec2 back = p + xz(away) * depth;
        if (clearOfRoute(p, back, prm.clearance_m)) {
          const int tex = bank.walls[rng.below(static_cast<int>(bank.walls.size()))];
          quads->push_back(wall(p, back, y_base, height + 1.0, tex, rng, 50.0f));
          footprints.emplace_back(p + xz(away) * 0.5, back);
        }
      }
      i = j + (rng.chance(prm.gap_probability) ? static_cast<size_t>(rng.uniform(2, 6)) : 0);
    }
  }

  void streetFurniture(int side, const TextureBank& bank) {
    const double kerb = prm.road_half_width_m;
    for (size_t i = 0; i < pts.size(); i += 3) {  // a slot every 6 m
      HashRng rng(hashCombine(hashCombine(seed, 0xCA25u + side), i));
      const Eigen::Vector3d r = side * right(i);
      const Eigen::Vector3d ground(pts[i].x(), groundY(static_cast<int>(i)), pts[i].z());
      if (rng.chance(prm.car_probability)) {
        const Eigen::Vector3d c = ground + r * (kerb - 1.0);
        const Vec2 f = xz(dirs[i]) * 2.2;
        if (routeDistance(xz(c) + f) > 3.2 && routeDistance(xz(c) - f) > 3.2 && routeDistance(xz(c)) > 3.2) {
          box(c, dirs[i], 4.2, 1.8, rng.uniform(1.4, 1.7),
              bank.cars[rng.below(static_cast<int>(bank.cars.size()))], rng, 90.0f, 90.0f);
        }
      }
      if (rng.chance(prm.tree_probability)) {
        const Eigen::Vector3d c = ground + r * (kerb + prm.pavement_width_m + rng.uniform(0.5, 2.0));
        if (routeDistance(xz(c)) > 4.0) {
          const double w = rng.uniform(3.0, 4.5), h = rng.uniform(5.0, 8.0);
          for (const Eigen::Vector3d& axis : {dirs[i], r}) {
            const Vec2 a = xz(c - axis * w / 2), b = xz(c + axis * w / 2);
            Quad q = wall(a, b, c.y(), h, bank.foliage, rng, 60.0f);
            q.shape = Quad::kTree;
            q.max_distance = 120.0f;
            quads->push_back(q);
          }
        }
      }
      if (std::fmod(i * kStep, prm.pole_spacing_m) < 3 * kStep && rng.chance(0.7)) {
        const Eigen::Vector3d c = ground + r * (kerb + 0.4);
        if (routeDistance(xz(c)) > 3.5) box(c, dirs[i], 0.22, 0.22, 6.0, bank.pole, rng, 60.0f, 90.0f);
      }
    }
  }
};

// The direction of travel on the ground at each route sample (over 3 samples each way).
std::vector<Eigen::Vector3d> groundDirections(const std::vector<Eigen::Vector3d>& route) {
  const size_t n = route.size();
  std::vector<Eigen::Vector3d> dirs;
  dirs.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    const size_t i0 = i >= 3 ? i - 3 : 0, i1 = std::min(n - 1, i + 3);
    Eigen::Vector3d d = route[i1] - route[i0];
    d.y() = 0;
    dirs.push_back(d.norm() > 1e-9 ? d.normalized() : Eigen::Vector3d(0, 0, 1));
  }
  return dirs;
}

// The route resampled every kStep metres of travel (at least three samples).
std::vector<Eigen::Vector3d> resampledRoute(const std::vector<Pose3>& route_T_w_c) {
  std::vector<Eigen::Vector3d> route{route_T_w_c.front().translation()};
  for (const auto& T : route_T_w_c) {
    const Eigen::Vector3d p = T.translation();
    while ((p - route.back()).norm() >= kStep)
      route.emplace_back(route.back() + (p - route.back()).normalized() * kStep);
  }
  if (route.size() < 3) route.emplace_back(route_T_w_c.back().translation() + Eigen::Vector3d(0, 0, kStep));
  return route;
}

}  // namespace

World World::build(const std::vector<Pose3>& route_T_w_c, TextureBank bank, const WorldParams& params,
                   uint64_t seed) {
  if (route_T_w_c.size() < 2) throw std::invalid_argument("World: the route needs at least 2 poses");
  if (bank.facades.empty()) throw std::invalid_argument("World: the texture bank has no façades");
  World w;
  w.bank_ = std::move(bank);
  w.params_ = params;

  w.route_ = resampledRoute(route_T_w_c);
  const size_t n = w.route_.size();
  w.route_dir_ = groundDirections(w.route_);

  // Bounds and the route-sample grid.
  double x0 = 1e18, z0 = 1e18, x1 = -1e18, z1 = -1e18;
  for (const auto& p : w.route_) {
    x0 = std::min(x0, p.x());
    z0 = std::min(z0, p.z());
    x1 = std::max(x1, p.x());
    z1 = std::max(z1, p.z());
  }
  const double margin = params.setback_max_m + 80.0;
  w.gx0_ = x0 - margin;
  w.gz0_ = z0 - margin;
  w.gw_ = static_cast<int>((x1 - x0 + 2 * margin) / w.cell_) + 1;
  w.gh_ = static_cast<int>((z1 - z0 + 2 * margin) / w.cell_) + 1;
  const int rw = static_cast<int>((x1 - x0 + 2 * margin) / kRouteCell) + 1;
  const int rh = static_cast<int>((z1 - z0 + 2 * margin) / kRouteCell) + 1;
  w.rgw_ = rw;
  w.rgh_ = rh;
  w.route_grid_.assign(static_cast<size_t>(rw) * rh, {});
  for (size_t i = 0; i < n; ++i) {
    const int cx = static_cast<int>((w.route_[i].x() - w.gx0_) / kRouteCell);
    const int cz = static_cast<int>((w.route_[i].z() - w.gz0_) / kRouteCell);
    w.route_grid_[static_cast<size_t>(cz) * rw + cx].push_back(static_cast<int>(i));
  }

  Builder b{params,
            seed,
            w.route_,
            w.route_dir_,
            [&w](double x, double z) { return w.nearestRouteSample(x, z); },
            {},
            &w.quads_};
  if (params.populate) {
    b.facadesOnSide(+1, w.bank_);
    b.facadesOnSide(-1, w.bank_);
    b.streetFurniture(+1, w.bank_);
    b.streetFurniture(-1, w.bank_);
  }
  w.indexQuads();

  if (params.rigid_ground) w.buildGroundHeights(x1 - x0 + 2 * margin, z1 - z0 + 2 * margin);

  // Ground materials by distance to the route.
  w.mx0_ = w.gx0_;
  w.mz0_ = w.gz0_;
  const int mw = static_cast<int>((x1 - x0 + 2 * margin) / w.mcell_) + 1;
  const int mh = static_cast<int>((z1 - z0 + 2 * margin) / w.mcell_) + 1;
  cv::Mat mask(mh, mw, CV_8U, cv::Scalar(255));
  for (size_t i = 0; i + 1 < n; ++i) {
    const cv::Point a(static_cast<int>((w.route_[i].x() - w.mx0_) / w.mcell_),
                      static_cast<int>((w.route_[i].z() - w.mz0_) / w.mcell_));
    const cv::Point c(static_cast<int>((w.route_[i + 1].x() - w.mx0_) / w.mcell_),
                      static_cast<int>((w.route_[i + 1].z() - w.mz0_) / w.mcell_));
    cv::line(mask, a, c, cv::Scalar(0), 1);
  }
  cv::Mat dist;
  cv::distanceTransform(mask, dist, cv::DIST_L2, 5);
  w.material_.create(mh, mw, CV_8U);
  const float road = static_cast<float>(params.road_half_width_m / w.mcell_);
  const float pave = static_cast<float>((params.road_half_width_m + params.pavement_width_m) / w.mcell_);
  for (int r = 0; r < mh; ++r) {
    for (int c = 0; c < mw; ++c) {
      const float d = dist.at<float>(r, c);
      w.material_.at<uint8_t>(r, c) = d < road ? 0 : (d < pave ? 1 : 2);
    }
  }
  return w;
}

void World::indexQuads() {
  grid_.assign(static_cast<size_t>(gw_) * gh_, {});
  max_quad_extent_ = 0;
  for (size_t k = 0; k < quads_.size(); ++k) {
    const Quad& q = quads_[k];
    const Eigen::Vector3f c = q.o + q.a * q.lu / 2 + q.b * q.lv / 2;
    const int cx = std::clamp(static_cast<int>((c.x() - gx0_) / cell_), 0, gw_ - 1);
    const int cz = std::clamp(static_cast<int>((c.z() - gz0_) / cell_), 0, gh_ - 1);
    grid_[static_cast<size_t>(cz) * gw_ + cx].push_back(static_cast<int>(k));
    max_quad_extent_ = std::max(max_quad_extent_, static_cast<double>(std::max(q.lu, q.lv)));
  }
}

void World::addQuads(const std::vector<Quad>& quads) {
  quads_.insert(quads_.end(), quads.begin(), quads.end());
  indexQuads();
}

int World::nearestRouteSample(double x, double z) const {
  const int rw = rgw_, rows = rgh_;
  const int cx = static_cast<int>((x - gx0_) / kRouteCell), cz = static_cast<int>((z - gz0_) / kRouteCell);
  int best = -1;
  double best_d = 1e18;
  for (int dz = -1; dz <= 1; ++dz) {
    for (int dx = -1; dx <= 1; ++dx) {
      const int gx = cx + dx, gz = cz + dz;
      if (gx < 0 || gz < 0 || gx >= rw || gz >= rows) continue;
      for (int i : route_grid_[static_cast<size_t>(gz) * rw + gx]) {
        const double d = std::hypot(route_[i].x() - x, route_[i].z() - z);
        if (d < best_d) {
          best_d = d;
          best = i;
        }
      }
    }
  }
  return best;
}

void World::quadsNear(double x, double z, double radius, std::vector<int>* out) const {
  out->clear();
  const double r = radius + max_quad_extent_;
  const int cx0 = std::max(0, static_cast<int>((x - r - gx0_) / cell_));
  const int cx1 = std::min(gw_ - 1, static_cast<int>((x + r - gx0_) / cell_));
  const int cz0 = std::max(0, static_cast<int>((z - r - gz0_) / cell_));
  const int cz1 = std::min(gh_ - 1, static_cast<int>((z + r - gz0_) / cell_));
  for (int cz = cz0; cz <= cz1; ++cz) {
    for (int cx = cx0; cx <= cx1; ++cx)
      for (int k : grid_[static_cast<size_t>(cz) * gw_ + cx]) out->push_back(k);
  }
}

void World::groundPlane(const Pose3& T_w_c, Eigen::Vector3d* n, double* d) const {
  const Eigen::Vector3d c = T_w_c.translation();
  const int i = nearestRouteSample(c.x(), c.z());
  Eigen::Vector3d down(0, 1, 0);
  if (i >= 0) {
    // Tilt with the route's grade over ±20 m so uphill roads rise in view.
    const int k = 10;
    const int i0 = std::max(0, i - k), i1 = std::min(static_cast<int>(route_.size()) - 1, i + k);
    Eigen::Vector3d t = route_[i1] - route_[i0];
    const double horiz = std::hypot(t.x(), t.z());
    if (horiz > 1.0) {
      const Eigen::Vector3d th = Eigen::Vector3d(t.x(), 0, t.z()) / horiz;
      const Eigen::Vector3d tangent = th + Eigen::Vector3d(0, t.y() / horiz, 0);
      const Eigen::Vector3d lateral(th.z(), 0, -th.x());
      down = tangent.cross(lateral).normalized();
      if (down.y() < 0) down = -down;
    }
  }
  *n = down;
  *d = down.dot(c + Eigen::Vector3d(0, params_.camera_height_m, 0));
}

void World::buildGroundHeights(double width_m, double depth_m) {
  // Each route sample's road height (camera_height_m under it) spread over the nodes within 3 sigma with
  // Gaussian weights: where the route passes itself (a U-turn, a revisit) both passes blend into one surface.
  constexpr double kSigma = 6.0;
  hx0_ = gx0_;  // the quad grid's origin
  hz0_ = gz0_;
  hw_ = static_cast<int>(width_m / hcell_) + 2;
  hh_ = static_cast<int>(depth_m / hcell_) + 2;
  const size_t nodes = static_cast<size_t>(hw_) * hh_;
  std::vector<double> sum(nodes, 0.0), weight(nodes, 0.0);
  const int reach = static_cast<int>(std::ceil(3 * kSigma / hcell_));
  for (const Eigen::Vector3d& r : route_) {
    const int ci = static_cast<int>(std::lround((r.x() - hx0_) / hcell_));
    const int cj = static_cast<int>(std::lround((r.z() - hz0_) / hcell_));
    for (int j = std::max(0, cj - reach); j <= std::min(hh_ - 1, cj + reach); ++j) {
      for (int i = std::max(0, ci - reach); i <= std::min(hw_ - 1, ci + reach); ++i) {
        const double dx = hx0_ + i * hcell_ - r.x(), dz = hz0_ + j * hcell_ - r.z();
        const double wgt = std::exp(-(dx * dx + dz * dz) / (2 * kSigma * kSigma));
        sum[static_cast<size_t>(j) * hw_ + i] += wgt * (r.y() + params_.camera_height_m);
        weight[static_cast<size_t>(j) * hw_ + i] += wgt;
      }
    }
  }
  // Nodes far from the route take their neighbours' mean, ring by ring outwards (only far ground is there).
  constexpr int kNeighbours[4][2] = {{-1, 0}, {1, 0}, {0, -1}, {0, 1}};
  ground_y_.assign(nodes, 0.0f);
  std::vector<char> known(nodes, 0);
  for (size_t k = 0; k < nodes; ++k) {
    if (weight[k] > 1e-3) {
      ground_y_[k] = static_cast<float>(sum[k] / weight[k]);
      known[k] = 1;
    }
  }
  for (bool grew = true; grew;) {
    grew = false;
    std::vector<char> next = known;
    for (int j = 0; j < hh_; ++j) {
      for (int i = 0; i < hw_; ++i) {
        const size_t k = static_cast<size_t>(j) * hw_ + i;
        if (known[k]) continue;
        double s = 0;
        int c = 0;
        for (const auto& d : kNeighbours) {
          const int a = i + d[0], b = j + d[1];
          if (a < 0 || b < 0 || a >= hw_ || b >= hh_ || !known[static_cast<size_t>(b) * hw_ + a]) continue;
          s += ground_y_[static_cast<size_t>(b) * hw_ + a];
          ++c;
        }
        if (c > 0) {
          ground_y_[k] = static_cast<float>(s / c);
          next[k] = 1;
          grew = true;
        }
      }
    }
    known.swap(next);
  }
}

double World::groundY(double x, double z, double* dy_dx, double* dy_dz) const {
  const double fx = std::clamp((x - hx0_) / hcell_, 0.0, hw_ - 1.000001);
  const double fz = std::clamp((z - hz0_) / hcell_, 0.0, hh_ - 1.000001);
  const int i = static_cast<int>(fx), j = static_cast<int>(fz);
  const double u = fx - i, v = fz - j;
  const size_t k = static_cast<size_t>(j) * hw_ + i;
  const double y00 = ground_y_[k], y10 = ground_y_[k + 1], y01 = ground_y_[k + hw_],
               y11 = ground_y_[k + hw_ + 1];
  if (dy_dx) *dy_dx = ((y10 - y00) * (1 - v) + (y11 - y01) * v) / hcell_;
  if (dy_dz) *dy_dz = ((y01 - y00) * (1 - u) + (y11 - y10) * u) / hcell_;
  return (y00 * (1 - u) + y10 * u) * (1 - v) + (y01 * (1 - u) + y11 * u) * v;
}

int World::groundMaterial(double x, double z) const {
  const int c = static_cast<int>((x - mx0_) / mcell_), r = static_cast<int>((z - mz0_) / mcell_);
  int m = 2;
  if (r >= 0 && c >= 0 && r < material_.rows && c < material_.cols) m = material_.at<uint8_t>(r, c);
  return m == 0 ? bank_.road : (m == 1 ? bank_.pavement : bank_.grass);
}

}  // namespace binloop::sim
