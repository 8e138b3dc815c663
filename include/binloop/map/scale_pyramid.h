#pragma once
// Per-level numbers of an ORB pyramid that matching and optimisation need: scale, its square (the
// variance of a keypoint's position grows with it), and the level at which a point at a given distance
// should be seen (ORB-SLAM2's PredictScale).
#include <cmath>
#include <vector>

namespace binloop {

struct ScalePyramid {
  float factor = 1.2f;
  std::vector<float> scale, sigma2, inv_sigma2;

  ScalePyramid() = default;
  ScalePyramid(float f, int levels) : factor(f) {
    float s = 1.f;
    for (int i = 0; i < levels; ++i, s *= f) {
      scale.push_back(s);
      sigma2.push_back(s * s);
      inv_sigma2.push_back(1.f / (s * s));
    }
  }
  int levels() const { return static_cast<int>(scale.size()); }
  /// The level a point seen from `distance` falls on, given the largest distance at which it is still
  /// seen at level 0.
  int predictLevel(float max_distance, float distance) const {
    const int l = static_cast<int>(std::ceil(std::log(max_distance / distance) / std::log(factor)));
    return l < 0 ? 0 : (l >= levels() ? levels() - 1 : l);
  }
};

}  // namespace binloop
