#include "binloop/types/stereo_camera.h"

#include <sstream>
#include <stdexcept>

namespace binloop {

Eigen::Matrix<double, 3, 4> StereoCamera::projectionMatrix(bool right) const {
  Eigen::Matrix<double, 3, 4> P;
  P << fx, 0, cx, right ? -fx * baseline_m : 0.0,  //
      0, fy, cy, 0,                                //
      0, 0, 1, 0;
  return P;
}

std::string StereoCamera::describe() const {
  std::ostringstream s;
  s << width << "x" << height << " fx=" << fx << " fy=" << fy << " cx=" << cx << " cy=" << cy
    << " baseline=" << baseline_m << " m (bf=" << bf() << ")";
  return s.str();
}

bool StereoCamera::operator==(const StereoCamera& o) const {
  return fx == o.fx && fy == o.fy && cx == o.cx && cy == o.cy && baseline_m == o.baseline_m &&
         width == o.width && height == o.height;
}

namespace {
StereoCamera make(double f, double cx, double cy, double bf, int w, int h) {
  StereoCamera c;
  c.fx = c.fy = f;
  c.cx = cx;
  c.cy = cy;
  c.baseline_m = bf / f;
  c.width = w;
  c.height = h;
  return c;
}
}  // namespace

StereoCamera kitti00Camera() { return make(718.856, 607.1928, 185.2157, 386.1448, 1241, 376); }

StereoCamera kittiCameraByName(const std::string& name) {
  if (name == "kitti00" || name == "kitti01" || name == "kitti02") return kitti00Camera();
  if (name == "kitti03") return make(721.5377, 609.5593, 172.854, 387.5744, 1242, 375);
  // Routes 04-12 were recorded on the same day as 04, with its calibration.
  static const char* const kSameAs04[] = {"kitti04", "kitti05", "kitti06", "kitti07", "kitti08",
                                          "kitti09", "kitti10", "kitti11", "kitti12"};
  for (const char* n : kSameAs04)
    if (name == n) return make(707.0912, 601.8873, 183.1104, 379.8145, 1226, 370);
  throw std::invalid_argument("unknown camera '" + name + "' (known: kitti00-kitti12, by route)");
}

}  // namespace binloop
