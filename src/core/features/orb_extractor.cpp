#include "binloop/features/orb_extractor.h"

#include <algorithm>
#include <opencv2/features2d.hpp>

#include "binloop/place/place_error.h"

namespace binloop {

namespace {

// Keeps `n` of `kps`, spread over a grid of cells about `cell` pixels wide: every cell gives its strongest
// keypoint, then its second strongest, and so on, until n are kept. Without this, a strongly textured
// surface (foliage, gravel, a busy façade) takes most of the budget, and every place that shows a
// similar texture looks alike to a bag of words.
std::vector<cv::KeyPoint> spreadOverGrid(std::vector<cv::KeyPoint> kps, cv::Size size, int cell, size_t n) {
  if (kps.size() <= n) return kps;
  const int cols = std::max(1, (size.width + cell - 1) / cell), rows = std::max(1, (size.height + cell - 1) / cell);
  std::vector<std::vector<cv::KeyPoint>> cells(static_cast<size_t>(cols * rows));
  for (const auto& k : kps) {
    const int cx = std::clamp(static_cast<int>(k.pt.x) / cell, 0, cols - 1);
    const int cy = std::clamp(static_cast<int>(k.pt.y) / cell, 0, rows - 1);
    cells[static_cast<size_t>(cy * cols + cx)].push_back(k);
  }
  for (auto& c : cells)  // strongest first; position breaks ties so the result never depends on sort internals
    std::sort(c.begin(), c.end(), [](const cv::KeyPoint& a, const cv::KeyPoint& b) {
      if (a.response != b.response) return a.response > b.response;
      if (a.octave != b.octave) return a.octave < b.octave;
      return a.pt.y != b.pt.y ? a.pt.y < b.pt.y : a.pt.x < b.pt.x;
    });
  std::vector<cv::KeyPoint> out;
  out.reserve(n);
  for (size_t rank = 0; out.size() < n; ++rank) {
    bool any = false;
    for (const auto& c : cells) {
      if (rank >= c.size()) continue;
      any = true;
      out.push_back(c[rank]);
      if (out.size() == n) break;
    }
    if (!any) break;
  }
  return out;
}

}  // namespace

OrbFeatures extractOrb(const cv::Mat& gray, const OrbParams& p) {
  if (gray.empty()) throw PlaceError("cannot extract ORB features from an empty image");
  if (gray.type() != CV_8UC1) throw PlaceError("ORB needs an 8-bit single-channel (grey) image");
  const int candidates = p.grid_cell_px > 0 ? p.features * p.candidates_factor : p.features;
  auto orb = cv::ORB::create(candidates, p.scale_factor, p.levels, 31, 0, 2, cv::ORB::HARRIS_SCORE, 31,
                             p.fast_threshold);
  OrbFeatures out;
  cv::Mat desc;
  if (p.grid_cell_px > 0) {
    std::vector<cv::KeyPoint> kps;
    orb->detect(gray, kps);
    out.keypoints = spreadOverGrid(std::move(kps), gray.size(), p.grid_cell_px, static_cast<size_t>(p.features));
    orb->compute(gray, out.keypoints, desc);
  } else {
    orb->detectAndCompute(gray, cv::noArray(), out.keypoints, desc);
  }
  out.descriptors = descriptorsFromMat(desc);
  return out;
}

}  // namespace binloop
