#pragma once
// Renders one camera's view of a World: the ground plane analytically per pixel, then every nearby quad
// rasterised with a z-buffer (occlusion is exact), sky where nothing is hit. Output is float grey and
// per-pixel depth (camera z, metres; +inf for sky).
#include <opencv2/core/mat.hpp>
#include <vector>

#include "binloop/sim/world.h"
#include "binloop/types/stereo_camera.h"

namespace binloop::sim {

class ViewRenderer {
 public:
  explicit ViewRenderer(double max_distance_m = 180.0, double near_m = 0.3)
      : max_distance_(max_distance_m), near_(near_m) {}
  /// `gray` becomes CV_32F, `depth` CV_32F, both camera.height x camera.width.
  void render(const World& world, const StereoCamera& camera, const Pose3& T_w_c, cv::Mat* gray,
              cv::Mat* depth);

 private:
  void drawGround(const World& world, const StereoCamera& cam, const Pose3& T_w_c, cv::Mat& gray,
                  cv::Mat& depth);
  void drawQuad(const World& world, const Quad& q, const StereoCamera& cam, const Pose3& T_w_c, cv::Mat& gray,
                cv::Mat& depth);
  double max_distance_, near_;
  std::vector<int> candidates_;
};

}  // namespace binloop::sim
