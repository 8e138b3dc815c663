#include "binloop/loop/correction_outbox.h"

#include <gtest/gtest.h>

namespace binloop {
namespace {

msg::CorrectionPtr correction(uint64_t sequence) {
  auto c = std::make_shared<msg::Correction>();
  c->sequence = sequence;
  return c;
}

std::vector<uint64_t> sequences(const std::vector<msg::CorrectionPtr>& cs) {
  std::vector<uint64_t> out;
  for (const auto& c : cs) out.push_back(c->sequence);
  return out;
}

// Mapping's updates go on without the correction sent: after the set number of them it goes again, and
// again after as many more while they still lack it; once an update shows it, nothing more is sent.
TEST(CorrectionOutbox, ACorrectionMappingsUpdatesLackIsSentAgainUntilTheyShowIt) {
  CorrectionOutbox box(3);
  box.sent(correction(1));
  EXPECT_TRUE(box.mappingSaw(0).empty());
  EXPECT_TRUE(box.mappingSaw(0).empty());
  EXPECT_EQ(sequences(box.mappingSaw(0)), std::vector<uint64_t>{1});
  EXPECT_TRUE(box.mappingSaw(0).empty());
  EXPECT_TRUE(box.mappingSaw(0).empty());
  EXPECT_EQ(sequences(box.mappingSaw(0)), std::vector<uint64_t>{1});
  for (int i = 0; i < 10; ++i) EXPECT_TRUE(box.mappingSaw(1).empty());
  EXPECT_EQ(box.resent(), 2u);
}

// A correction on its way: mapping's queue holds a few keyframes made before it, then applies it.
TEST(CorrectionOutbox, ACorrectionOnItsWayIsNotSentAgain) {
  CorrectionOutbox box(3);
  box.sent(correction(1));
  EXPECT_TRUE(box.mappingSaw(0).empty());
  EXPECT_TRUE(box.mappingSaw(0).empty());
  EXPECT_TRUE(box.mappingSaw(1).empty());
  box.sent(correction(2));
  EXPECT_TRUE(box.mappingSaw(1).empty());
  EXPECT_TRUE(box.mappingSaw(1).empty());
  EXPECT_TRUE(box.mappingSaw(2).empty());
  EXPECT_EQ(box.resent(), 0u);
}

// Local mapping restarted from an autosave made before corrections 2 and 3 (its count went back): both go
// again, in sequence, even though it had shown 3 before.
TEST(CorrectionOutbox, AMappingThatWentBackGetsEveryCorrectionItLacksInSequence) {
  CorrectionOutbox box(2);
  for (uint64_t s = 1; s <= 3; ++s) box.sent(correction(s));
  EXPECT_TRUE(box.mappingSaw(3).empty());
  EXPECT_TRUE(box.mappingSaw(1).empty());
  bool gap = true;
  EXPECT_EQ(sequences(box.mappingSaw(1, &gap)), (std::vector<uint64_t>{2, 3}));
  EXPECT_FALSE(gap);
}

// Only the last `kept` are kept: a mapping that lacks older ones cannot be brought back, and is said to.
TEST(CorrectionOutbox, CorrectionsNoLongerKeptAreAGap) {
  CorrectionOutbox box(1, 2);
  for (uint64_t s = 1; s <= 4; ++s) box.sent(correction(s));
  bool gap = false;
  EXPECT_EQ(sequences(box.mappingSaw(1, &gap)), (std::vector<uint64_t>{3, 4}));
  EXPECT_TRUE(gap);
  EXPECT_THROW(CorrectionOutbox(0), std::invalid_argument);
}

}  // namespace
}  // namespace binloop
