// loops.csv: what run writes is what eval-slam reads back, and a broken file is an error naming the line.
#include "binloop/pipeline/loop_log.h"

#include <gtest/gtest.h>

#include "binloop/io/data_error.h"
#include <fstream>
#include <sstream>

#include "support/test_support.h"

using namespace binloop;

namespace {

SlamPipeline::LoopLogEntry entry(uint64_t query, uint64_t frame, const std::string& status, uint64_t match_frame) {
  SlamPipeline::LoopLogEntry e;
  auto c = std::make_shared<msg::LoopCandidates>();
  c->query = query;
  c->query_frame = frame;
  c->model = "hbow";
  c->status = "found";
  c->detail = "a \"quoted\", detail";
  c->candidates.push_back({7, 0.25, 2.0});
  c->accepted = 7;
  e.active = c;
  auto l = std::make_shared<msg::LoopClosure>();
  l->query = query;
  l->query_frame = frame;
  l->match_frame = match_frame;
  l->model = "hbow";
  l->status = status;
  l->inliers = 120;
  l->correction_m = 1.5;
  l->detail = "numbers, with a comma";
  e.closures.push_back(l);
  auto s = std::make_shared<msg::LoopCandidates>(*c);
  s->model = "vlad";
  s->shadow = true;
  s->accepted = kNoId;
  e.shadow.push_back(s);
  return e;
}

}  // namespace

TEST(LoopLog, WhatIsWrittenIsReadBack) {
  test::TempDir tmp;
  writeLoopLog(tmp / "loops.csv", {entry(1, 30, "too_few_matches", 2), entry(2, 40, "accepted", 3)});
  const std::vector<LoggedLoop> loops = readLoopLog(tmp / "loops.csv");
  ASSERT_EQ(loops.size(), 2u);  // shadow rows carry no closure
  EXPECT_EQ(loops[0].status, "too_few_matches");
  EXPECT_EQ(loops[1].status, "accepted");
  EXPECT_EQ(loops[1].query_frame, 40u);
  EXPECT_EQ(loops[1].match_frame, 3u);
  EXPECT_EQ(loops[1].inliers, 120);
  EXPECT_DOUBLE_EQ(loops[1].correction_m, 1.5);
}

TEST(LoopLog, ABrokenFileNamesTheLine) {
  test::TempDir tmp;
  writeLoopLog(tmp / "loops.csv", {entry(1, 30, "accepted", 2)});
  std::ifstream in(tmp / "loops.csv");
  std::stringstream text;
  text << in.rdbuf();
  test::writeText(tmp / "short.csv", text.str() + "1,2,3\n");
  EXPECT_THROW_WITH(readLoopLog(tmp / "short.csv"), DataError, "short.csv:4: 3 fields, expected 21");
  test::writeText(tmp / "header.csv", "frame,model\n");
  EXPECT_THROW_WITH(readLoopLog(tmp / "header.csv"), DataError, "not a loops.csv");
  EXPECT_THROW_WITH(readLoopLog(tmp / "missing.csv"), DataError, "cannot open");
}
