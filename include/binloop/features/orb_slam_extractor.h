#pragma once
// binloop's own ORB extractor, built the way ORB-SLAM2's is: a scale pyramid; FAST in ~30-pixel cells with
// a lower threshold where a cell finds nothing; a quadtree that keeps the strongest corner of each node so
// that every level's budget is spread over the whole image; intensity-centroid orientation; 256-bit
// rotated BRIEF on the blurred level. Tracking and stereo matching need features from everywhere in the
// image (a corner per region, not the hundred best of the busiest texture), and they need the pyramid
// itself for sub-pixel stereo, so the pyramid is a value the caller can keep.
//
// Two sets of BRIEF tests. kGaussian (the default): binloop's own, 256 pairs drawn from an isotropic
// Gaussian (sigma = 31/5 px, BRIEF's "G II" layout) by HashRng with a fixed seed, each point inside the
// radius-15 orientation disc. kOrbLearned: ORB's learned rBRIEF tests, computed by OpenCV's ORB for
// binloop's keypoints on the extractor's own level at the extractor's angle (OpenCV's ORB on the whole image
// gives the same bits at level 0 and within a few bits above, where it resizes its own pyramid). The learned
// tests' bits are balanced and less correlated (the steered Gaussian ones are biased, as the ORB paper
// found), which the place models gain from; but on renders they survive a 24 m gap worse, and recovery after
// 20 missing frames fails with them, so the SLAM keeps the Gaussian tests by default (docs/decisions.md,
// "ORB's learned BRIEF tests"). `learn-pattern` learns a pattern as ORB learned rBRIEF. It is the one
// extractor of binloop: SLAM, `train`, `eval-loops` and the benchmarks all use it (with the same settings by
// default), and every model file records the settings it was trained with.
#include <array>
#include <cmath>
#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <opencv2/core/types.hpp>
#include <string>
#include <vector>

#include "binloop/features/extractor_settings.h"
#include "binloop/types/binary_descriptor.h"

namespace binloop {

/// One BRIEF test: bit = I(a) < I(b) on the smoothed level (briefSmoothed), with a = (ax, ay) and b = (bx,
/// by) in level pixels relative to the keypoint, rotated by its angle first. |a|, |b| <= 15.
struct BriefTest {
  int8_t ax, ay, bx, by;
};
using BriefPattern = std::array<BriefTest, 256>;

/// binloop's Gaussian pattern (BriefPatternKind::kGaussian): bit i of a descriptor is test i (bit i % 64 of
/// word i / 64).
const BriefPattern& briefPattern();

/// The level BRIEF reads: Gaussian 7x7, sigma 2, reflected border (ORB-SLAM2's), so that single-pixel tests
/// are stable under noise.
void briefSmoothed(const cv::Mat& level, cv::Mat& out);

/// Where test point (x, y) lands around a keypoint with `angle_deg`, exactly as the extractor rounds it.
/// cs, sn: cos and sin of the angle, as briefRotation() gives them.
inline cv::Point rotatedTestPoint(float x, float y, float cs, float sn) {
  return {cvRound(x * cs - y * sn), cvRound(x * sn + y * cs)};
}
inline void briefRotation(float angle_deg, float* cs, float* sn) {
  const float a = angle_deg * static_cast<float>(CV_PI / 180.0);
  *cs = std::cos(a);
  *sn = std::sin(a);
}

/// Which 256 BRIEF tests make the descriptor. Model files record it (ExtractorSettings::kind): a vocabulary
/// trained on one pattern's bits is refused for the other's.
enum class BriefPatternKind { kOrbLearned, kGaussian };

/// "orb" or "gaussian"; briefPatternFromName throws FeatureError for another name.
const char* briefPatternName(BriefPatternKind k);
BriefPatternKind briefPatternFromName(const std::string& name);

struct OrbFeatures {
  std::vector<cv::KeyPoint> keypoints;
  Descriptors descriptors;
};

struct OrbSlamParams {
  int features = 2000;        // budget over all levels (the result may exceed it by a few, as ORB-SLAM2's)
  float scale_factor = 1.2f;  // between consecutive pyramid levels
  int levels = 8;
  int ini_fast = 20;  // FAST threshold tried first in every cell
  int min_fast = 7;   // tried in a cell only when ini_fast found nothing there (low-contrast regions)
  int cell_px = 30;   // FAST cell side, level pixels
  BriefPatternKind pattern = BriefPatternKind::kGaussian;

  bool operator==(const OrbSlamParams& o) const;
  bool operator!=(const OrbSlamParams& o) const { return !(*this == o); }
};

/// What a model header records for descriptors of OrbSlamExtractor(p) on images scaled down to a longer
/// side of `max_side` first (0: full size, as SLAM extracts). Pass it as
/// RecognizerOptions::extractor.expected (or ExtractorCheck::expected) when loading a model that this
/// extractor's descriptors will feed.
ExtractorSettings extractorSettings(const OrbSlamParams& p, int max_side = 0);

/// Level 0 is the image itself (its header shares the caller's pixels); level i is level i-1 resized
/// (bilinear) to round(size / scale_factor^i).
struct ImagePyramid {
  std::vector<cv::Mat> levels;
  std::vector<float> scale;  // scale_factor^i: level-0 pixels per level-i pixel
};

/// Throws FeatureError for an empty or non-8-bit single-channel image, or levels < 1, scale_factor <= 1.
ImagePyramid buildPyramid(const cv::Mat& gray, int levels, float scale_factor);

/// Keypoints come out level by level. pt is in level-0 pixels, octave is the level, angle in degrees
/// [0, 360), response is the FAST score, size is 31 * scale. Deterministic; safe to call from several
/// threads on one instance.
class OrbSlamExtractor {
 public:
  /// Throws FeatureError for parameters out of range (features < 1, levels < 1, scale_factor <= 1,
  /// thresholds < 1 or min_fast > ini_fast, cell_px < 8).
  explicit OrbSlamExtractor(const OrbSlamParams& p = {});

  /// Throws FeatureError for an empty or non-8-bit single-channel image.
  OrbFeatures extract(const cv::Mat& gray) const;
  /// From a pyramid made by pyramid() (or buildPyramid with the same levels and factor), so that the
  /// caller keeps it for stereo. Throws FeatureError when its level count or scales differ.
  OrbFeatures extract(const ImagePyramid& pyramid) const;
  ImagePyramid pyramid(const cv::Mat& gray) const { return buildPyramid(gray, p_.levels, p_.scale_factor); }

  const OrbSlamParams& params() const { return p_; }
  /// ORB-SLAM2's per-level budget: a geometric series with ratio 1/scale_factor summing to `features`
  /// (level area shrinks by scale_factor^2, but the count by scale_factor only, so coarse levels keep a
  /// useful share).
  const std::vector<int>& featuresPerLevel() const { return per_level_; }

 private:
  OrbSlamParams p_;
  std::vector<int> per_level_;
};

}  // namespace binloop
