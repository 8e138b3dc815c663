// Ids carry their issuer in the top byte and a counter below it (include/binloop/map/ids.h).
#include "binloop/map/ids.h"

#include <gtest/gtest.h>

#include <unordered_set>

namespace binloop {
namespace {

const IdIssuer kAllIssuers[] = {IdIssuer::kTracking, IdIssuer::kLocalMapping, IdIssuer::kLoopClosing};

TEST(Ids, FirstIdsAreOneTwoThreeAndNeverNone) {
  IdCounter c(IdIssuer::kTracking);
  EXPECT_EQ(c.issued(), 0u);
  const uint64_t a = c.next(), b = c.next(), d = c.next();
  EXPECT_NE(a, kNoId);
  EXPECT_EQ(counterOf(a), 1u);
  EXPECT_EQ(counterOf(b), 2u);
  EXPECT_EQ(counterOf(d), 3u);
  EXPECT_EQ(c.issued(), 3u);
}

TEST(Ids, IssuersNeverCollide) {
  std::unordered_set<uint64_t> seen;
  IdCounter t(IdIssuer::kTracking), m(IdIssuer::kLocalMapping), l(IdIssuer::kLoopClosing);
  // Interleaved, as stages running side by side would issue them; the same counters in each stage.
  for (int i = 0; i < 1000; ++i) {
    EXPECT_TRUE(seen.insert(t.next()).second);
    EXPECT_TRUE(seen.insert(m.next()).second);
    EXPECT_TRUE(seen.insert(l.next()).second);
  }
  EXPECT_EQ(seen.size(), 3000u);
  EXPECT_EQ(seen.count(kNoId), 0u);
}

TEST(Ids, IssuerAndCounterRoundTrip) {
  for (IdIssuer who : kAllIssuers) {
    IdCounter c(who);
    for (uint64_t n = 1; n <= 100; ++n) {
      const uint64_t id = c.next();
      EXPECT_EQ(issuerOf(id), who) << "id " << id;
      EXPECT_EQ(counterOf(id), n) << "id " << id;
      // The id is exactly issuer byte | counter.
      EXPECT_EQ(id, (uint64_t(static_cast<uint8_t>(who)) << 56) | n);
    }
  }
}

TEST(Ids, IssuerValuesAreTheWireFormat) {
  // Part of the message format (ids.h: "never renumber").
  EXPECT_EQ(static_cast<int>(IdIssuer::kTracking), 1);
  EXPECT_EQ(static_cast<int>(IdIssuer::kLocalMapping), 2);
  EXPECT_EQ(static_cast<int>(IdIssuer::kLoopClosing), 3);
}

TEST(Ids, CounterUsesAllFiftySixBits) {
  const uint64_t max_counter = (uint64_t{1} << 56) - 1;
  for (IdIssuer who : kAllIssuers) {
    const uint64_t id = (uint64_t(static_cast<uint8_t>(who)) << 56) | max_counter;
    EXPECT_EQ(issuerOf(id), who);
    EXPECT_EQ(counterOf(id), max_counter);
  }
  EXPECT_EQ(counterOf(kNoId), 0u);
}

TEST(Ids, SameCounterFromDifferentIssuersDiffers) {
  IdCounter a(IdIssuer::kTracking), b(IdIssuer::kLocalMapping);
  const uint64_t x = a.next(), y = b.next();
  EXPECT_EQ(counterOf(x), counterOf(y));
  EXPECT_NE(x, y);
  EXPECT_NE(issuerOf(x), issuerOf(y));
}

// A stage restored from an older state (an autosave) does not know how many ids its predecessor issued after
// it: a new session starts beyond every id of the old one, at a multiple of 2^32.
TEST(Ids, ANewSessionIssuesNoIdOfThePreviousOne) {
  IdCounter before(IdIssuer::kLocalMapping);
  for (int i = 0; i < 1000; ++i) before.next();
  IdCounter restored(IdIssuer::kLocalMapping);
  restored.restore(400);  // the autosave's count
  restored.startSession();
  const uint64_t first = restored.next();
  EXPECT_EQ(counterOf(first), (uint64_t{1} << 32) + 1);
  EXPECT_GT(first, before.next());
  restored.startSession();  // and again after a second restart
  EXPECT_EQ(counterOf(restored.next()), (uint64_t{2} << 32) + 1);
}

// A stage that takes another's place (a reset, a loaded map) starts its session after the other's ids and its
// own, whichever counter is further on.
TEST(Ids, ASessionAfterAnotherCounterIssuesNoIdOfEither) {
  IdCounter old_one(IdIssuer::kTracking);
  for (int i = 0; i < 5; ++i) old_one.next();
  old_one.startSession();
  old_one.next();  // the old one is in its second session
  IdCounter fresh(IdIssuer::kTracking);
  fresh.startSessionAfter(old_one.issued());
  EXPECT_EQ(counterOf(fresh.next()), (uint64_t{2} << 32) + 1);
  IdCounter ahead(IdIssuer::kTracking);
  for (int i = 0; i < 3; ++i) ahead.startSession();
  ahead.startSessionAfter(7);  // its own count is further on than the other's
  EXPECT_EQ(counterOf(ahead.next()), (uint64_t{4} << 32) + 1);
}

}  // namespace
}  // namespace binloop
