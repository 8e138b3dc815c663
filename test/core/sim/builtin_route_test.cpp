#include "binloop/sim/builtin_route.h"

#include "support/test_support.h"

TEST(BuiltinRoute, ClosesTheLoopAndRevisits) {
  const auto r = binloop::sim::loopRoute(120, 200, 15, 8, 10, 1.3);
  const double lap = 2 * 170 + 2 * 90 + 2 * M_PI * 15;
  ASSERT_NEAR(r.size(), 1.3 * lap / 0.8, 2);
  // After one lap the car is back at the start, facing the same way: a same-direction revisit.
  const size_t one_lap = static_cast<size_t>(std::round(lap / 0.8));
  EXPECT_LT((r[one_lap].translation() - r[0].translation()).norm(), 1.0);
  EXPECT_LT(Eigen::AngleAxisd(r[one_lap].rotation().transpose() * r[0].rotation()).angle(), 0.05);
  // Steps are 0.8 m everywhere, corners included.
  for (size_t i = 1; i < r.size(); ++i)
    EXPECT_NEAR((r[i].translation() - r[i - 1].translation()).norm(), 0.8, 0.01);
  // The far side of the block is 120 m across.
  double max_x = 0;
  for (const auto& T : r) max_x = std::max(max_x, std::abs(T.translation().x()));
  EXPECT_NEAR(max_x, 120, 0.5);
}
