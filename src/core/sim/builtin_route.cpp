#include "binloop/sim/builtin_route.h"

#include <cmath>

namespace binloop::sim {

std::vector<Pose3> loopRoute(double width_m, double length_m, double radius_m, double speed_mps, double hz,
                             double laps) {
  // Arc-length parametrisation of the rounded rectangle, driven clockwise seen from above (right turns).
  const double sx = length_m - 2 * radius_m, sz = width_m - 2 * radius_m, arc = M_PI / 2 * radius_m;
  const double lap = 2 * sx + 2 * sz + 4 * arc;
  std::vector<Pose3> route;
  const double ds = speed_mps / hz;
  for (double s = 0; s < laps * lap; s += ds) {
    double t = std::fmod(s, lap);
    // Walk the pieces: straight, corner, straight, corner, ... keeping position and heading.
    Eigen::Vector2d p(0, 0);  // (x, z)
    double heading = 0;       // angle from +z towards +x
    const double pieces[8] = {sx, arc, sz, arc, sx, arc, sz, arc};
    for (int k = 0; k < 8 && t > 0; ++k) {
      const double len = std::min(t, pieces[k]);
      if (k % 2 == 0) {
        p += len * Eigen::Vector2d(std::sin(heading), std::cos(heading));
      } else {
        const double a = len / radius_m;  // right turn about a centre on the right
        const Eigen::Vector2d right(std::cos(heading), -std::sin(heading));
        const Eigen::Vector2d centre = p + radius_m * right;
        const Eigen::Vector2d rel = p - centre;
        const double c = std::cos(a), sn = std::sin(a);
        // Clockwise in (x, z) as seen with +z up the page and +x to the right.
        p = centre + Eigen::Vector2d(c * rel.x() + sn * rel.y(), -sn * rel.x() + c * rel.y());
        heading += a;
      }
      t -= len;
    }
    Pose3 T = Pose3::Identity();
    T.linear() = Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitY()).toRotationMatrix();
    T.translation() = Eigen::Vector3d(p.x(), 0, p.y());
    route.push_back(T);
  }
  return route;
}

}  // namespace binloop::sim
