#pragma once
// A grey texture with a mip pyramid, sampled bilinearly with wrap-around. Rendering distant surfaces from
// the right mip level is what keeps ORB features stable between frames instead of shimmering with aliasing.
#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <vector>

namespace binloop::sim {

class Texture {
 public:
  Texture() = default;
  /// `img` must be CV_8UC1 with power-of-two sides (so that wrap-around is a bit mask).
  explicit Texture(const cv::Mat& img);
  int width() const { return w_; }
  int height() const { return h_; }
  int levels() const { return static_cast<int>(mips_.size()); }
  /// Bilinear sample at texel coordinates (u, v) of level 0, from mip `level` (clamped), wrapping.
  float sample(float u, float v, int level) const;
  const cv::Mat& level(int l) const { return mips_[l]; }
  float mean() const { return mean_; }

 private:
  int w_ = 0, h_ = 0;
  float mean_ = 0;
  std::vector<cv::Mat> mips_;
};

}  // namespace binloop::sim
