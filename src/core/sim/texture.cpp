#include "binloop/sim/texture.h"

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace binloop::sim {

namespace {
bool isPow2(int n) { return n > 0 && (n & (n - 1)) == 0; }
}  // namespace

Texture::Texture(const cv::Mat& img) {
  if (img.type() != CV_8UC1 || !isPow2(img.cols) || !isPow2(img.rows))
    throw std::invalid_argument("Texture: needs CV_8UC1 with power-of-two sides");
  w_ = img.cols;
  h_ = img.rows;
  mean_ = static_cast<float>(cv::mean(img)[0]);
  mips_.push_back(img.clone());
  while (mips_.back().cols > 4 && mips_.back().rows > 4) {
    cv::Mat half;
    cv::resize(mips_.back(), half, cv::Size(mips_.back().cols / 2, mips_.back().rows / 2), 0, 0,
               cv::INTER_AREA);
    mips_.push_back(half);
  }
}

float Texture::sample(float u, float v, int level) const {
  if (level < 0) level = 0;
  if (level >= levels()) level = levels() - 1;
  const cv::Mat& m = mips_[level];
  const float s = 1.0f / static_cast<float>(1 << level);
  const float x = u * s - 0.5f, y = v * s - 0.5f;
  const float fx = std::floor(x), fy = std::floor(y);
  const float ax = x - fx, ay = y - fy;
  const int wm = m.cols - 1, hm = m.rows - 1;
  const int x0 = static_cast<int>(fx) & wm, y0 = static_cast<int>(fy) & hm;
  const int x1 = (x0 + 1) & wm, y1 = (y0 + 1) & hm;
  const uint8_t* r0 = m.ptr<uint8_t>(y0);
  const uint8_t* r1 = m.ptr<uint8_t>(y1);
  const float top = r0[x0] + ax * (r0[x1] - r0[x0]);
  const float bot = r1[x0] + ax * (r1[x1] - r1[x0]);
  return top + ay * (bot - top);
}

}  // namespace binloop::sim
