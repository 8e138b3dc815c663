// BoundedQueue: the blocking queue between stage threads (include/binloop/pipeline/bounded_queue.h).
#include "binloop/pipeline/bounded_queue.h"

#include <gtest/gtest.h>

#include <chrono>
#include <future>
#include <memory>
#include <thread>
#include <vector>

namespace binloop {
namespace {

using namespace std::chrono_literals;

// Long enough for a thread that could go on to have done so; short enough to keep the tests quick.
constexpr auto kBlocked = 100ms;
constexpr auto kWakes = 10s;

// Closes the queue when a test ends early (a failed ASSERT), so no thread stays blocked and the futures'
// destructors return. Declare it after the futures.
template <typename T>
struct CloseOnExit {
  BoundedQueue<T>& q;
  ~CloseOnExit() { q.close(); }
};

TEST(BoundedQueue, KeepsOrder) {
  BoundedQueue<int> q(100);
  for (int i = 0; i < 50; ++i) EXPECT_TRUE(q.push(i));
  EXPECT_EQ(q.size(), 50u);
  for (int i = 0; i < 50; ++i) {
    auto v = q.pop();
    ASSERT_TRUE(v.has_value());
    EXPECT_EQ(*v, i);
  }
  EXPECT_EQ(q.size(), 0u);
  EXPECT_FALSE(q.tryPop().has_value());
}

TEST(BoundedQueue, KeepsOrderAcrossThreadsThroughASmallQueue) {
  BoundedQueue<int> q(3);
  constexpr int kN = 20000;
  auto producer = std::async(std::launch::async, [&] {
    for (int i = 0; i < kN; ++i)
      if (!q.push(i)) return false;
    q.close();
    return true;
  });
  CloseOnExit<int> guard{q};
  int expected = 0;
  while (auto v = q.pop()) {
    ASSERT_EQ(*v, expected);
    ++expected;
    EXPECT_LE(q.size(), 3u);
  }
  EXPECT_EQ(expected, kN);
  EXPECT_TRUE(producer.get());
}

TEST(BoundedQueue, FullQueueBlocksTheProducerUntilAPop) {
  BoundedQueue<int> q(2);
  EXPECT_TRUE(q.push(1));
  EXPECT_TRUE(q.push(2));
  auto producer = std::async(std::launch::async, [&] { return q.push(3); });
  CloseOnExit<int> guard{q};
  EXPECT_EQ(producer.wait_for(kBlocked), std::future_status::timeout) << "push into a full queue returned";
  EXPECT_EQ(q.size(), 2u);
  EXPECT_EQ(q.pop(), std::optional<int>(1));
  ASSERT_EQ(producer.wait_for(kWakes), std::future_status::ready) << "a pop did not wake the producer";
  EXPECT_TRUE(producer.get());
  EXPECT_EQ(q.size(), 2u);
  EXPECT_EQ(q.pop(), std::optional<int>(2));
  EXPECT_EQ(q.pop(), std::optional<int>(3));
}

TEST(BoundedQueue, TryPopAlsoWakesTheProducer) {
  BoundedQueue<int> q(1);
  EXPECT_TRUE(q.push(1));
  auto producer = std::async(std::launch::async, [&] { return q.push(2); });
  CloseOnExit<int> guard{q};
  EXPECT_EQ(producer.wait_for(kBlocked), std::future_status::timeout);
  EXPECT_EQ(q.tryPop(), std::optional<int>(1));
  ASSERT_EQ(producer.wait_for(kWakes), std::future_status::ready);
  EXPECT_TRUE(producer.get());
  EXPECT_EQ(q.tryPop(), std::optional<int>(2));
}

TEST(BoundedQueue, CloseWakesAWaitingConsumer) {
  BoundedQueue<int> q(4);
  auto consumer = std::async(std::launch::async, [&] { return q.pop(); });
  CloseOnExit<int> guard{q};
  EXPECT_EQ(consumer.wait_for(kBlocked), std::future_status::timeout) << "pop on an empty queue returned";
  q.close();
  ASSERT_EQ(consumer.wait_for(kWakes), std::future_status::ready) << "close() did not wake the consumer";
  EXPECT_FALSE(consumer.get().has_value());
}

TEST(BoundedQueue, CloseWakesEveryWaitingConsumer) {
  BoundedQueue<int> q(4);
  std::vector<std::future<std::optional<int>>> consumers;
  for (int i = 0; i < 3; ++i) consumers.push_back(std::async(std::launch::async, [&] { return q.pop(); }));
  CloseOnExit<int> guard{q};
  std::this_thread::sleep_for(kBlocked);
  q.close();
  for (auto& c : consumers) {
    ASSERT_EQ(c.wait_for(kWakes), std::future_status::ready);
    EXPECT_FALSE(c.get().has_value());
  }
}

TEST(BoundedQueue, PopDrainsAfterCloseThenReturnsNullopt) {
  BoundedQueue<int> q(4);
  EXPECT_TRUE(q.push(1));
  EXPECT_TRUE(q.push(2));
  q.close();
  EXPECT_FALSE(q.push(3)) << "push after close";
  EXPECT_EQ(q.pop(), std::optional<int>(1));
  EXPECT_EQ(q.pop(), std::optional<int>(2));
  EXPECT_EQ(q.pop(), std::nullopt);
  EXPECT_EQ(q.pop(), std::nullopt);
  EXPECT_EQ(q.tryPop(), std::nullopt);
}

TEST(BoundedQueue, CloseWakesABlockedProducer) {
  BoundedQueue<int> q(1);
  EXPECT_TRUE(q.push(1));
  auto producer = std::async(std::launch::async, [&] { return q.push(2); });
  CloseOnExit<int> guard{q};
  EXPECT_EQ(producer.wait_for(kBlocked), std::future_status::timeout);
  q.close();
  ASSERT_EQ(producer.wait_for(kWakes), std::future_status::ready) << "close() did not wake the producer";
  EXPECT_FALSE(producer.get()) << "a push that was waiting when the queue closed must report it was dropped";
  EXPECT_EQ(q.pop(), std::optional<int>(1));
  EXPECT_EQ(q.pop(), std::nullopt);
}

TEST(BoundedQueue, MoveOnlyItems) {
  BoundedQueue<std::unique_ptr<int>> q(2);
  EXPECT_TRUE(q.push(std::make_unique<int>(5)));
  EXPECT_TRUE(q.push(std::make_unique<int>(6)));
  auto a = q.pop();
  ASSERT_TRUE(a && *a);
  EXPECT_EQ(**a, 5);
  auto b = q.tryPop();
  ASSERT_TRUE(b && *b);
  EXPECT_EQ(**b, 6);
}

}  // namespace
}  // namespace binloop
