#include "binloop/map/keypoint_grid.h"

#include <algorithm>
#include <cmath>

namespace binloop {

KeypointGrid::KeypointGrid(const std::vector<msg::KeyPoint>& kps, int width, int height, int cell_px)
    : kps_(kps),
      cols_(std::max(1, (width + cell_px - 1) / cell_px)),
      rows_(std::max(1, (height + cell_px - 1) / cell_px)),
      cell_(cell_px),
      cells_(static_cast<size_t>(cols_) * rows_) {
  for (size_t i = 0; i < kps.size(); ++i) {
    const int cx = std::clamp(static_cast<int>(kps[i].x) / cell_, 0, cols_ - 1);
    const int cy = std::clamp(static_cast<int>(kps[i].y) / cell_, 0, rows_ - 1);
    cells_[static_cast<size_t>(cy) * cols_ + cx].push_back(static_cast<int>(i));
  }
}

std::vector<int> KeypointGrid::near(float x, float y, float r, int min_level, int max_level) const {
  std::vector<int> out;
  if (kps_.empty() || !std::isfinite(x) || !std::isfinite(y)) return out;
  if (!std::isfinite(r) || r < 0) return out;
  // Cells are clamped on both sides: keypoints outside the image were binned into the border cells.
  auto cell = [&](float v, int n) {
    return std::clamp(static_cast<int>(std::floor(std::clamp(v, -1e6f, 1e6f) / cell_)), 0, n - 1);
  };
  const int x0 = cell(x - r, cols_), x1 = cell(x + r, cols_);
  const int y0 = cell(y - r, rows_), y1 = cell(y + r, rows_);
  for (int cy = y0; cy <= y1; ++cy) {
    for (int cx = x0; cx <= x1; ++cx) {
      for (int i : cells_[static_cast<size_t>(cy) * cols_ + cx]) {
        const msg::KeyPoint& k = kps_[i];
        if (min_level >= 0 && k.octave < min_level) continue;
        if (max_level >= 0 && k.octave > max_level) continue;
        if (std::abs(k.x - x) <= r && std::abs(k.y - y) <= r) out.push_back(i);
      }
    }
  }
  return out;
}

}  // namespace binloop
