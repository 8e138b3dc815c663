#include "binloop/sim/level_revisits.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

namespace binloop::sim {

namespace {

double planarDistance(const Pose3& a, const Pose3& b) {
  const Eigen::Vector3d d = a.translation() - b.translation();
  return std::hypot(d.x(), d.z());
}

}  // namespace

LevelResult levelRevisits(const std::vector<Pose3>& route, const LevelParams& p) {
  if (!(p.radius_m > 0) || !(p.ramp_m > 0))
    throw std::invalid_argument("levelRevisits: radius and ramp must be > 0");
  const size_t n = route.size();
  LevelResult out;
  out.route = route;
  if (n == 0) return out;
  std::vector<double> s(n, 0.0);  // path length up to each frame
  for (size_t i = 1; i < n; ++i)
    s[i] = s[i - 1] + (route[i].translation() - route[i - 1].translation()).norm();

  // In frame order, so that a third pass takes the height the second was given (which is the first's).
  std::vector<std::optional<double>> offset(n);
  for (size_t i = 0; i < n; ++i) {
    if (i < p.min_frames_apart) continue;
    double best = p.radius_m;
    std::optional<size_t> near;
    for (size_t j = 0; j + p.min_frames_apart <= i; ++j) {
      const double d = planarDistance(route[i], route[j]);
      if (d < best) best = d, near = j;
    }
    if (!near) continue;
    offset[i] = route[*near].translation().y() + offset[*near].value_or(0) - route[i].translation().y();
    ++out.revisit_frames;
  }

  // Frames between revisits: the offsets of the revisits on either side, interpolated along the path when
  // both are within reach, else each faded to nothing over ramp_m.
  std::vector<double> final_offset(n, 0.0);
  std::optional<size_t> prev;
  std::vector<std::optional<size_t>> next_of(n);
  for (size_t i = n; i-- > 0;)
    next_of[i] = offset[i] ? std::optional<size_t>(i) : (i + 1 < n ? next_of[i + 1] : std::nullopt);
  for (size_t i = 0; i < n; ++i) {
    if (offset[i]) {
      final_offset[i] = *offset[i];
      prev = i;
      continue;
    }
    const std::optional<size_t> next = next_of[i];
    if (prev && next && s[*next] - s[*prev] <= 2 * p.ramp_m) {
      const double t = (s[i] - s[*prev]) / std::max(1e-9, s[*next] - s[*prev]);
      final_offset[i] = (1 - t) * *offset[*prev] + t * *offset[*next];
      continue;
    }
    double o = 0;
    if (prev) o += *offset[*prev] * std::max(0.0, 1 - (s[i] - s[*prev]) / p.ramp_m);
    if (next) o += *offset[*next] * std::max(0.0, 1 - (s[*next] - s[i]) / p.ramp_m);
    final_offset[i] = o;
  }
  for (size_t i = 0; i < n; ++i) {
    out.route[i].translation().y() += final_offset[i];
    out.max_shift_m = std::max(out.max_shift_m, std::abs(final_offset[i]));
  }
  return out;
}

}  // namespace binloop::sim
