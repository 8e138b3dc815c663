#include "binloop/features/orb_extractor.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "binloop/place/place_error.h"
#include "binloop/util/hash_random.h"
#include "support/test_support.h"

using namespace binloop;

namespace {

// A 192x192 patch of dense high-contrast noise (foliage-like) in one corner; elsewhere a sparse pattern of
// weaker blobs.
constexpr int kPatch = 192;
cv::Mat busyPatch() {
  cv::Mat img(480, 960, CV_8UC1, cv::Scalar(128));
  HashRng rng(5);
  for (int y = 20; y < img.rows - 20; y += 60)
    for (int x = 20; x < img.cols - 20; x += 60)
      cv::rectangle(img, {x, y}, {x + 12 + (x + y) % 9, y + 10 + (x * y) % 7}, cv::Scalar(rng.chance(0.5) ? 90 : 166), -1);
  for (int y = 0; y < kPatch; ++y)
    for (int x = 0; x < kPatch; ++x) img.at<uint8_t>(y, x) = static_cast<uint8_t>(rng.below(256));
  return img;
}

int inPatch(const OrbFeatures& f) {
  int n = 0;
  for (const auto& k : f.keypoints) n += k.pt.x < kPatch && k.pt.y < kPatch;
  return n;
}

}  // namespace

TEST(OrbExtractor, GridSpreadsFeaturesBeyondTheBusiestTexture) {
  const cv::Mat img = busyPatch();
  OrbParams strongest;
  strongest.grid_cell_px = 0;
  OrbParams grid;  // default: 64-pixel cells
  const OrbFeatures a = extractOrb(img, strongest), b = extractOrb(img, grid);
  ASSERT_EQ(a.descriptors.size(), 1000u);
  ASSERT_EQ(b.descriptors.size(), b.keypoints.size());
  EXPECT_GE(b.descriptors.size(), 900u);
  const int patch_a = inPatch(a), patch_b = inPatch(b);
  EXPECT_GT(patch_a, 700) << "the noise patch (8 % of the image) takes most of the strongest-first budget";
  EXPECT_LT(patch_b, patch_a / 2) << patch_a << " -> " << patch_b;
  std::printf("features in the noise patch: %d strongest-first, %d spread\n", patch_a, patch_b);
}

TEST(OrbExtractor, SameImageSameFeatures) {
  const cv::Mat img = busyPatch();
  const OrbFeatures a = extractOrb(img), b = extractOrb(img);
  ASSERT_EQ(a.descriptors.size(), b.descriptors.size());
  for (size_t i = 0; i < a.descriptors.size(); ++i) EXPECT_EQ(hamming(a.descriptors[i], b.descriptors[i]), 0);
}

TEST(OrbExtractor, RefusesEmptyAndColourImages) {
  EXPECT_THROW_WITH(extractOrb(cv::Mat()), PlaceError, "empty image");
  EXPECT_THROW_WITH(extractOrb(cv::Mat(10, 10, CV_8UC3)), PlaceError, "8-bit single-channel");
}
