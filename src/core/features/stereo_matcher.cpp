#include "binloop/features/stereo_matcher.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>
#include <utility>

#include "binloop/features/feature_error.h"

namespace binloop {

namespace {

void check(bool ok, const std::string& what) {
  if (!ok) throw FeatureError("stereo matching: " + what);
}

void checkSide(const OrbFeatures& f, const ImagePyramid& pyr, const char* side) {
  check(f.keypoints.size() == f.descriptors.size(),
        std::string(side) + " side has " + std::to_string(f.keypoints.size()) + " keypoints but " +
            std::to_string(f.descriptors.size()) + " descriptors");
  check(!pyr.levels.empty() && pyr.scale.size() == pyr.levels.size(),
        std::string(side) + " pyramid is empty or has no scale per level");
  for (const auto& k : f.keypoints) {
    if (k.octave < 0 || k.octave >= static_cast<int>(pyr.levels.size())) {
      check(false, std::string(side) + " keypoint of octave " + std::to_string(k.octave) +
                       " but the pyramid has " + std::to_string(pyr.levels.size()) + " levels");
    }
  }
}

// Right keypoints by image row, as one array with row offsets: a right keypoint is listed on every row
// within its band, so a left keypoint finds its candidates by its own row alone.
struct RowIndex {
  std::vector<int> start, ids;
  RowIndex(const OrbFeatures& right, const ImagePyramid& pyr, int rows, float band) : start(rows + 1, 0) {
    auto span = [&](const cv::KeyPoint& k) {
      const float r = band * pyr.scale[k.octave];
      return std::make_pair(std::max(0, static_cast<int>(std::floor(k.pt.y - r))),
                            std::min(rows - 1, static_cast<int>(std::ceil(k.pt.y + r))));
    };
    for (const auto& k : right.keypoints) {
      const auto [lo, hi] = span(k);
      for (int y = lo; y <= hi; ++y) ++start[y + 1];
    }
    for (int y = 0; y < rows; ++y) start[y + 1] += start[y];
    ids.resize(start[rows]);
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (int i = 0; i < static_cast<int>(right.keypoints.size()); ++i) {
      const auto [lo, hi] = span(right.keypoints[i]);
      for (int y = lo; y <= hi; ++y) ids[fill[y]++] = i;
    }
  }
};

// SAD of two windows after taking an offset off each, so that a brightness offset between the cameras
// (exposure, vignetting) costs nothing. The offset is the window's mean: ORB-SLAM2's centre pixel is the
// corner itself, unlike its neighbours by construction, so one pixel of slide changes the offset of all 121
// pixels and the SAD curve turns steep and lopsided (on a KITTI frame shifted by 12 px, 47 % of matches
// within 0.2 px, against 92 % with the mean). In units of 1/n grey level, to stay in integers.
int offsetSad(const cv::Mat& l, cv::Point pl, const cv::Mat& r, cv::Point pr, int w, bool centre_pixel) {
  const int n = (2 * w + 1) * (2 * w + 1);
  int offset = 0;  // (mean or centre of l) - (that of r), times n
  if (centre_pixel) {
    offset = n * (static_cast<int>(l.at<uint8_t>(pl)) - static_cast<int>(r.at<uint8_t>(pr)));
  } else {
    for (int dy = -w; dy <= w; ++dy) {
      const uint8_t* a = l.ptr<uint8_t>(pl.y + dy) + pl.x;
      const uint8_t* b = r.ptr<uint8_t>(pr.y + dy) + pr.x;
      for (int dx = -w; dx <= w; ++dx) offset += a[dx] - b[dx];
    }
  }
  int sad = 0;
  for (int dy = -w; dy <= w; ++dy) {
    const uint8_t* a = l.ptr<uint8_t>(pl.y + dy) + pl.x;
    const uint8_t* b = r.ptr<uint8_t>(pr.y + dy) + pr.x;
    for (int dx = -w; dx <= w; ++dx) sad += std::abs(n * (a[dx] - b[dx]) - offset);
  }
  return sad;
}

// Vertex offset of the curve through (-1, s1), (0, s2), (1, s3) with s2 the least. A parabola (ORB-SLAM2)
// reaches +-1; the equiangular fit (two lines of opposite slope, the shape of SAD near a match) stays
// within +-0.5.
float subPixelOffset(float s1, float s2, float s3, StereoMatchParams::SubPixelFit fit) {
  if (fit == StereoMatchParams::SubPixelFit::kEquiangular) {
    const float rise = std::max(s1, s3) - s2;
    return rise > 0 ? (s1 - s3) / (2.f * rise) : 0.f;
  }
  const float curvature = s1 + s3 - 2.f * s2;
  return curvature > 0 ? (s1 - s3) / (2.f * curvature) : 0.f;
}

struct Refined {
  float right_x;
  int sad;
};

// Slides the left window over the right level around the descriptor match; a curve through the best SAD
// and its neighbours gives the sub-pixel offset. False when a window leaves the image, the best is at the
// end of the slide (the true minimum may lie beyond it), or the vertex is over a pixel away (a flat or
// noisy SAD curve).
bool refine(const cv::KeyPoint& kl, float right_x0, const ImagePyramid& lp, const ImagePyramid& rp,
            const StereoMatchParams& p, Refined* out) {
  const cv::Mat& L = lp.levels[kl.octave];
  const cv::Mat& R = rp.levels[kl.octave];
  const float scale = lp.scale[kl.octave];
  const int w = p.sad_half_window, reach = p.sad_search_px;
  const cv::Point pl(cvRound(kl.pt.x / scale), cvRound(kl.pt.y / scale));
  const int ur0 = cvRound(right_x0 / scale);
  if (pl.y - w < 0 || pl.y + w >= L.rows || pl.x - w < 0 || pl.x + w >= L.cols) return false;
  if (ur0 - reach - w < 0 || ur0 + reach + w >= R.cols) return false;
  std::vector<int> sads(2 * reach + 1);
  int best = -reach;
  for (int inc = -reach; inc <= reach; ++inc) {
    sads[inc + reach] = offsetSad(L, pl, R, {ur0 + inc, pl.y}, w, p.centre_pixel_offset);
    if (sads[inc + reach] < sads[best + reach]) best = inc;
  }
  if (best == -reach || best == reach) return false;
  const float delta =
      subPixelOffset(static_cast<float>(sads[best + reach - 1]), static_cast<float>(sads[best + reach]),
                     static_cast<float>(sads[best + reach + 1]), p.fit);
  if (delta < -1.f || delta > 1.f) return false;
  out->right_x = scale * (static_cast<float>(ur0 + best) + delta);
  out->sad = sads[best + reach] / ((2 * w + 1) * (2 * w + 1));
  return true;
}

}  // namespace

bool StereoMatchParams::operator==(const StereoMatchParams& o) const {
  return max_hamming == o.max_hamming && min_depth_m == o.min_depth_m && row_band_px == o.row_band_px &&
         sad_half_window == o.sad_half_window && sad_search_px == o.sad_search_px &&
         sad_outlier_factor == o.sad_outlier_factor && close_depth_baselines == o.close_depth_baselines &&
         centre_pixel_offset == o.centre_pixel_offset && fit == o.fit;
}

StereoMatches matchStereo(const OrbFeatures& left, const ImagePyramid& left_pyramid, const OrbFeatures& right,
                          const ImagePyramid& right_pyramid, const StereoCamera& cam,
                          const StereoMatchParams& p) {
  check(p.max_hamming >= 1 && p.sad_half_window >= 1 && p.sad_half_window <= 15 && p.sad_search_px >= 1 &&
            p.row_band_px >= 0 && p.sad_outlier_factor > 0 && p.min_depth_m >= 0,
        "parameters out of range (max_hamming >= 1, 1 <= sad_half_window <= 15, sad_search_px >= 1, "
        "row_band_px >= 0, sad_outlier_factor > 0, min_depth_m >= 0)");
  checkSide(left, left_pyramid, "left");
  checkSide(right, right_pyramid, "right");
  check(cam.bf() > 0,
        "the camera needs fx > 0 and a positive baseline, got fx·b = " + std::to_string(cam.bf()));
  check(left_pyramid.levels.size() == right_pyramid.levels.size(),
        "left and right pyramids differ in levels");
  for (size_t i = 0; i < left_pyramid.levels.size(); ++i) {
    check(left_pyramid.levels[i].size() == right_pyramid.levels[i].size() &&
              left_pyramid.levels[i].type() == CV_8UC1 && right_pyramid.levels[i].type() == CV_8UC1,
          "pyramid level " + std::to_string(i) + " differs between left and right or is not 8-bit grey");
  }

  const size_t n = left.keypoints.size();
  StereoMatches out;
  out.right_x.assign(n, -1.f);
  out.depth.assign(n, -1.f);
  const int rows = left_pyramid.levels[0].rows;
  const RowIndex index(right, right_pyramid, rows, p.row_band_px);
  const float bf = static_cast<float>(cam.bf());
  const float max_disparity =
      static_cast<float>(cam.bf() / (p.min_depth_m > 0 ? p.min_depth_m : cam.baseline_m));

  std::vector<std::pair<int, int>> sad_of;  // (SAD, left index) of every refined match
  sad_of.reserve(n);
  for (size_t il = 0; il < n; ++il) {
    const cv::KeyPoint& kl = left.keypoints[il];
    const int row = static_cast<int>(kl.pt.y);
    if (row < 0 || row >= rows) continue;
    const float min_x = kl.pt.x - max_disparity, max_x = kl.pt.x;
    int best_dist = p.max_hamming, best = -1;
    for (int c = index.start[row]; c < index.start[row + 1]; ++c) {
      const cv::KeyPoint& kr = right.keypoints[index.ids[c]];
      if (kr.octave < kl.octave - 1 || kr.octave > kl.octave + 1 || kr.pt.x < min_x || kr.pt.x > max_x)
        continue;
      const int d = hamming(left.descriptors[il], right.descriptors[index.ids[c]]);
      if (d < best_dist) {
        best_dist = d;
        best = index.ids[c];
      }
    }
    Refined r;
    if (best < 0 || !refine(kl, right.keypoints[best].pt.x, left_pyramid, right_pyramid, p, &r)) continue;
    float disparity = kl.pt.x - r.right_x;
    if (disparity < 0 || disparity >= max_disparity) continue;
    if (disparity <= 0) {  // keep a point at infinity usable: a tiny disparity, far but finite
      disparity = 0.01f;
      r.right_x = kl.pt.x - disparity;
    }
    out.right_x[il] = r.right_x;
    out.depth[il] = bf / disparity;
    sad_of.emplace_back(r.sad, static_cast<int>(il));
  }

  if (!sad_of.empty()) {
    auto mid = sad_of.begin() + sad_of.size() / 2;
    std::nth_element(sad_of.begin(), mid, sad_of.end());
    out.sad_threshold = p.sad_outlier_factor * static_cast<float>(mid->first);
    for (const auto& [sad, il] : sad_of) {
      if (static_cast<float>(sad) > out.sad_threshold) {
        out.right_x[il] = out.depth[il] = -1.f;
        ++out.rejected_by_sad;
      }
    }
  }
  out.matched = static_cast<int>(sad_of.size()) - out.rejected_by_sad;
  return out;
}

bool isCloseDepth(float depth_m, const StereoCamera& cam, const StereoMatchParams& p) {
  return depth_m > 0 && depth_m < p.close_depth_baselines * cam.baseline_m;
}

}  // namespace binloop
