#pragma once
// Learning a BRIEF test pattern the way ORB learned rBRIEF (Rublee et al. 2011, "ORB: an efficient
// alternative to SIFT or SURF", section 4.3), for binloop's extractor (features/orb_slam_extractor.h):
//  1. every candidate test compares the smoothed level at two points of the radius-15 disc, rotated by the
//     keypoint angle (the extractor's own test form); pairs closer than `min_separation` in x and y are left
//     out (ORB enumerated non-overlapping 5x5 sub-windows);
//  2. every candidate is run over a large set of oriented keypoints of training images (PatchSamples: the
//     smoothed value at each disc point around each keypoint, read as the extractor reads it);
//     Not in ORB: a candidate whose two values lie within `tie_margin` grey levels of each other on more than
//     `max_tie_share` of the keypoints is left out too; noise flips such a bit, so two views of one corner
//     disagree on it. Off by default: balanced tests are near-ties more often than biased ones, and a
//     filter strict enough to matter (0.25 at margin 5) leaves only tests as biased as Gaussian pairs;
//  3. the candidates are ordered by the distance of their mean from 0.5; each is oriented (a < b or b < a)
//     so that its mean is the nearer to 0.5;
//  4. greedily, in that order, a test is kept when its absolute correlation with every kept test is below a
//     threshold; when fewer than `bits` survive, the threshold is raised by a step and the walk starts again.
// Deterministic: keypoints are sampled with a seeded HashRng per image, and nothing depends on thread timing.
#include <cstdint>
#include <string>
#include <vector>

#include "binloop/features/orb_slam_extractor.h"

namespace binloop {

/// The integer points (x, y) with x^2 + y^2 <= 15^2, row by row: where a test point may lie.
const std::vector<cv::Point>& briefDisc();

/// values[p][k]: the smoothed level at disc point p, rotated by keypoint k's angle, around keypoint k.
struct PatchSamples {
  std::vector<std::vector<uint8_t>> values;  // briefDisc().size() columns
  size_t keypoints() const { return values.empty() ? 0 : values[0].size(); }
  /// Appends `more`'s keypoints after these.
  void append(const PatchSamples& more);
};

/// Extracts `gray` with `extractor` (keypoints, octaves and angles as the SLAM gets them) and samples up to
/// `max_keypoints` of them, chosen at random by HashRng(seed) (all of them when there are fewer).
/// Keypoint order: as extracted. Throws FeatureError for an image the extractor refuses.
PatchSamples samplePatches(const cv::Mat& gray, const OrbSlamExtractor& extractor, size_t max_keypoints,
                           uint64_t seed);

/// Bit `test` of every sampled keypoint, as the extractor would compute it.
std::vector<uint8_t> testBits(const PatchSamples& s, const BriefTest& test);

struct PatternLearningOptions {
  int bits = 256;                // tests to keep (the extractor's table needs exactly 256)
  int min_separation = 5;        // a candidate's points differ by at least this in x or in y (pixels)
  double start_threshold = 0.1;  // first |correlation| bound of the greedy walk
  double threshold_step = 0.01;  // raise per failed walk
  size_t pool = 12000;           // the walk looks at this many best-balanced candidates at most
  int tie_margin = 5;            // |I(a) - I(b)| <= this is a near-tie
  double max_tie_share = 1;      // candidates with more near-ties than this share are left out (1: none)
  int threads = 2;
};

struct LearnedPattern {
  std::vector<BriefTest> tests;     // `bits` of them, in the order kept (best-balanced first)
  double threshold = 0;             // |correlation| bound the walk succeeded with
  size_t candidates = 0;            // tests enumerated (after the separation and near-tie filters)
  size_t walked = 0;                // candidates the successful walk looked at
  std::vector<double> mean;         // P(bit = 1) of each kept test on the samples
  double mean_abs_correlation = 0;  // between kept tests, on the samples
  double max_abs_correlation = 0;
  double tie_share = 0;  // mean near-tie share of the kept tests
};

/// Throws FeatureError when there are no samples or options are out of range, or when the pool cannot give
/// `bits` tests below |r| = 1.
LearnedPattern learnBriefPattern(const PatchSamples& s, const PatternLearningOptions& o);

}  // namespace binloop
