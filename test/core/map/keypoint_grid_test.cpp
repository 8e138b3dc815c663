// KeypointGrid::near must give exactly what a scan over every keypoint gives
// (include/binloop/map/keypoint_grid.h).
#include "binloop/map/keypoint_grid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <utility>

namespace binloop {
namespace {

// Uniform in [lo, hi) from the raw 32-bit output of mt19937 (whose sequence the standard fixes; its
// distributions are not).
struct Rng {
  std::mt19937 g;
  explicit Rng(uint32_t seed) : g(seed) {}
  float uniform(float lo, float hi) { return lo + (hi - lo) * static_cast<float>(g() >> 8) / float(1 << 24); }
  int below(int n) { return static_cast<int>(g() % static_cast<uint32_t>(n)); }
};

msg::KeyPoint kp(float x, float y, int octave = 0) {
  msg::KeyPoint k;
  k.x = x;
  k.y = y;
  k.octave = static_cast<uint8_t>(octave);
  return k;
}

std::vector<int> bruteForce(const std::vector<msg::KeyPoint>& kps, float x, float y, float r, int min_level,
                            int max_level) {
  std::vector<int> out;
  for (size_t i = 0; i < kps.size(); ++i) {
    const msg::KeyPoint& k = kps[i];
    if (min_level >= 0 && k.octave < min_level) continue;
    if (max_level >= 0 && k.octave > max_level) continue;
    if (std::abs(k.x - x) <= r && std::abs(k.y - y) <= r) out.push_back(static_cast<int>(i));
  }
  return out;
}

std::vector<int> sorted(std::vector<int> v) {
  std::sort(v.begin(), v.end());
  return v;
}

constexpr int kW = 1241, kH = 376;  // KITTI 00

std::vector<msg::KeyPoint> randomKeypoints(Rng& rng, int n, int w, int h) {
  std::vector<msg::KeyPoint> kps;
  for (int i = 0; i < n; ++i)
    kps.push_back(kp(rng.uniform(0, float(w)), rng.uniform(0, float(h)), rng.below(8)));
  return kps;
}

void expectSameAsBruteForce(uint32_t seed, int cell_px) {
  Rng rng(seed);
  const auto kps = randomKeypoints(rng, 3000, kW, kH);
  const KeypointGrid grid(kps, kW, kH, cell_px);
  size_t found = 0;
  for (int q = 0; q < 3000; ++q) {
    // Centres also a little outside the image, as projections of points near its border are.
    const float x = rng.uniform(-30, kW + 30), y = rng.uniform(-30, kH + 30);
    const float r = q % 10 == 0 ? rng.uniform(0, 200) : rng.uniform(0, 40);
    int min_level = rng.below(10) - 1, max_level = rng.below(10) - 1;  // -1 = no bound, up to 8
    if (q % 3 == 0) min_level = max_level = -1;
    const auto expected = bruteForce(kps, x, y, r, min_level, max_level);
    const auto got = grid.near(x, y, r, min_level, max_level);
    ASSERT_EQ(sorted(got), expected) << "seed " << seed << " cell " << cell_px << " query " << q << " at ("
                                     << x << ", " << y << ") r " << r << " levels [" << min_level << ", "
                                     << max_level << "]";
    found += got.size();
  }
  EXPECT_GT(found, 3000u) << "the queries should find something";
}

TEST(KeypointGrid, NearEqualsBruteForce) {
  for (uint32_t seed : {1u, 2u, 3u}) expectSameAsBruteForce(seed, 16);
}

TEST(KeypointGrid, NearEqualsBruteForceForOtherCellSizes) {
  for (int cell : {1, 7, 30, 64, 2000}) expectSameAsBruteForce(42, cell);
}

TEST(KeypointGrid, NoDuplicatesInResult) {
  Rng rng(7);
  const auto kps = randomKeypoints(rng, 2000, kW, kH);
  const KeypointGrid grid(kps, kW, kH);
  for (int q = 0; q < 200; ++q) {
    auto got = sorted(grid.near(rng.uniform(0, kW), rng.uniform(0, kH), rng.uniform(0, 100)));
    EXPECT_EQ(std::adjacent_find(got.begin(), got.end()), got.end());
  }
}

TEST(KeypointGrid, LevelBoundsAreInclusive) {
  std::vector<msg::KeyPoint> kps;
  for (int o = 0; o < 8; ++o) kps.push_back(kp(100.5f, 50.5f, o));  // one per level, same place
  const KeypointGrid grid(kps, kW, kH);
  EXPECT_EQ(sorted(grid.near(100, 50, 2)), (std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7}));
  EXPECT_EQ(sorted(grid.near(100, 50, 2, 2, 4)), (std::vector<int>{2, 3, 4}));
  EXPECT_EQ(sorted(grid.near(100, 50, 2, 3, 3)), (std::vector<int>{3}));
  EXPECT_EQ(sorted(grid.near(100, 50, 2, 5, -1)), (std::vector<int>{5, 6, 7}));
  EXPECT_EQ(sorted(grid.near(100, 50, 2, -1, 1)), (std::vector<int>{0, 1}));
  EXPECT_TRUE(grid.near(100, 50, 2, 5, 4).empty());
  EXPECT_TRUE(grid.near(100, 50, 2, 8, -1).empty());
}

TEST(KeypointGrid, RadiusIsASquareWithInclusiveEdges) {
  const std::vector<msg::KeyPoint> kps = {kp(100, 100), kp(104, 104), kp(104.01f, 100), kp(96, 100)};
  const KeypointGrid grid(kps, kW, kH);
  EXPECT_EQ(sorted(grid.near(100, 100, 4)), (std::vector<int>{0, 1, 3}));  // (104, 104) is in: |dx|,|dy| <= r
  EXPECT_EQ(sorted(grid.near(100, 100, 0)), (std::vector<int>{0}));
}

TEST(KeypointGrid, KeypointsAtTheImageBorder) {
  const float e = 1e-3f;
  const std::vector<msg::KeyPoint> kps = {
      kp(0, 0),        kp(kW - e, 0),   kp(0, kH - e),        kp(kW - e, kH - e),
      kp(kW / 2.f, 0), kp(0, kH / 2.f), kp(kW - e, kH / 2.f), kp(kW / 2.f, kH - e)};
  for (int cell : {16, 30, 1000}) {
    const KeypointGrid grid(kps, kW, kH, cell);
    for (size_t i = 0; i < kps.size(); ++i) {
      // At the keypoint itself, and from just outside the image (a projection falling off its border).
      EXPECT_EQ(grid.near(kps[i].x, kps[i].y, 0), (std::vector<int>{int(i)}))
          << "cell " << cell << " kp " << i;
      const float ox = kps[i].x < 1 ? -1.5f : kps[i].x > kW - 1 ? kW + 1.5f : kps[i].x;
      const float oy = kps[i].y < 1 ? -1.5f : kps[i].y > kH - 1 ? kH + 1.5f : kps[i].y;
      EXPECT_EQ(grid.near(ox, oy, 2), (std::vector<int>{int(i)})) << "cell " << cell << " kp " << i;
      EXPECT_TRUE(grid.near(ox, oy, 1).empty()) << "cell " << cell << " kp " << i;
    }
    EXPECT_EQ(grid.near(kW / 2.f, kH / 2.f, 1e4f).size(), kps.size());
  }
}

TEST(KeypointGrid, ImageSizeNotAMultipleOfTheCell) {
  // 1241 = 77 * 16 + 9: the last column of cells is partial.
  const std::vector<msg::KeyPoint> kps = {kp(1240.9f, 375.9f), kp(1232.f, 368.f), kp(1231.9f, 367.9f)};
  const KeypointGrid grid(kps, kW, kH);
  EXPECT_EQ(sorted(grid.near(1236, 372, 5)), (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(sorted(grid.near(1240, 375, 1)), (std::vector<int>{0}));
}

// Keypoints outside the image are binned into the border cells; a query there must still scan those cells.
TEST(KeypointGrid, KeypointsOutsideTheImageAreFoundLikeBruteForce) {
  const std::vector<msg::KeyPoint> kps = {kp(-0.5f, 10), kp(10, -0.5f), kp(kW + 20.f, 10), kp(10, kH + 20.f)};
  const KeypointGrid grid(kps, kW, kH);
  for (size_t i = 0; i < kps.size(); ++i)
    EXPECT_EQ(grid.near(kps[i].x, kps[i].y, 0.25f), (std::vector<int>{int(i)})) << "kp " << i;
}

TEST(KeypointGrid, OutlivesItsSourceVector) {
  Rng rng(5);
  auto kps = std::make_unique<std::vector<msg::KeyPoint>>(randomKeypoints(rng, 500, kW, kH));
  const std::vector<msg::KeyPoint> copy = *kps;
  KeypointGrid grid(*kps, kW, kH);
  // The owner moves its keypoints away (as a Frame being moved does) and then frees them.
  std::vector<msg::KeyPoint> moved = std::move(*kps);
  kps->clear();
  kps->shrink_to_fit();
  kps.reset();
  moved.assign(moved.size(), kp(-1000, -1000, 7));  // and overwrites the buffer it took
  for (int q = 0; q < 300; ++q) {
    const float x = rng.uniform(0, kW), y = rng.uniform(0, kH), r = rng.uniform(0, 50);
    ASSERT_EQ(sorted(grid.near(x, y, r)), bruteForce(copy, x, y, r, -1, -1));
  }
  // A grid that is itself moved or copied answers the same.
  KeypointGrid moved_grid = std::move(grid);
  KeypointGrid copied_grid = moved_grid;
  EXPECT_EQ(sorted(moved_grid.near(600, 200, 50)), bruteForce(copy, 600, 200, 50, -1, -1));
  EXPECT_EQ(sorted(copied_grid.near(600, 200, 50)), bruteForce(copy, 600, 200, 50, -1, -1));
}

TEST(KeypointGrid, EmptyOrDefaultGridAndNonFiniteQueries) {
  EXPECT_TRUE(KeypointGrid().near(10, 10, 100).empty());
  EXPECT_TRUE(KeypointGrid({}, kW, kH).near(10, 10, 100).empty());
  const KeypointGrid grid({kp(10, 10)}, kW, kH);
  EXPECT_TRUE(grid.near(std::numeric_limits<float>::quiet_NaN(), 10, 5).empty());
  EXPECT_TRUE(grid.near(10, std::numeric_limits<float>::infinity(), 5).empty());
  EXPECT_TRUE(grid.near(10, 10, -1).empty());
  EXPECT_EQ(grid.near(10, 10, 1), (std::vector<int>{0}));
}

}  // namespace
}  // namespace binloop
