// lowerThisThreadPriority (include/binloop/util/thread_priority.h): background work yields to tracking.
#include "binloop/util/thread_priority.h"

#include <gtest/gtest.h>

#include <thread>

#if defined(__linux__)
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

namespace binloop {
namespace {

#if defined(__linux__)
int threadNice() { return getpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid))); }

TEST(ThreadPriority, LowersOnlyTheCallingThread) {
  const int before = threadNice();
  if (before > 19 - 5) GTEST_SKIP() << "this process already runs at nice " << before;
  int inside = 0;
  bool lowered = false;
  std::thread t([&] {
    lowered = lowerThisThreadPriority(5);
    inside = threadNice();
  });
  t.join();
  EXPECT_TRUE(lowered);
  EXPECT_EQ(inside, before + 5);
  EXPECT_EQ(threadNice(), before) << "the caller's own thread is left as it was";
}
#endif

}  // namespace
}  // namespace binloop
