// lowerThisThreadPriority (include/binloop/util/thread_priority.h): background work yields to tracking.
#include "binloop/util/thread_priority.h"

#include <gtest/gtest.h>

#include <thread>

namespace binloop {
namespace {

#if defined(__linux__)
TEST(ThreadPriority, LowersOnlyTheCallingThread) {
  const int before = thisThreadNice();
  if (before > 19 - 5) GTEST_SKIP() << "this process already runs at nice " << before;
  int inside = 0;
  bool lowered = false;
  std::thread t([&] {
    lowered = lowerThisThreadPriority(5);
    inside = thisThreadNice();
  });
  t.join();
  EXPECT_TRUE(lowered);
  EXPECT_EQ(inside, before + 5);
  EXPECT_EQ(thisThreadNice(), before) << "the caller's own thread is left as it was";
}
#endif

}  // namespace
}  // namespace binloop
