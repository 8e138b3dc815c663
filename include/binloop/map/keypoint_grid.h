#pragma once
// Keypoints binned by image cell, so that "keypoints within r pixels of (x, y)" touches a few cells
// instead of every keypoint; each projection search asks this thousands of times per frame.
#include <vector>

#include "binloop/messages/keyframe.h"

namespace binloop {

class KeypointGrid {
 public:
  KeypointGrid() = default;
  KeypointGrid(const std::vector<msg::KeyPoint>& kps, int width, int height, int cell_px = 16);
  /// Indices of keypoints with |dx|, |dy| <= r and min_level <= octave <= max_level (-1: no bound).
  std::vector<int> near(float x, float y, float r, int min_level = -1, int max_level = -1) const;

 private:
  std::vector<msg::KeyPoint> kps_;  // a copy: the grid stays valid when its owner moves
  int cols_ = 0, rows_ = 0, cell_ = 16;
  std::vector<std::vector<int>> cells_;
};

}  // namespace binloop
