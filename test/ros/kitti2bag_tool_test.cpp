// kitti2bag as a user runs it: exit codes and the exact lines printed.
#include "support/test_support.h"

namespace {
binloop::test::CommandResult run(const std::string& args) {
  return binloop::test::runCommand(std::string(BINLOOP_TOOL_DIR) + "/kitti2bag " + args);
}
}  // namespace

TEST(Kitti2bagTool, ConvertsThenRefusesToOverwrite) {
  const std::string seq = binloop::test::sharedData("kitti/sample_00");
  BINLOOP_REQUIRE_DATA(seq);
  binloop::test::TempDir tmp;
  const auto ok = run(seq + " " + (tmp / "s.bag") + " --poses " + seq + "/poses.txt");
  EXPECT_EQ(ok.code, 0) << ok.out;
  EXPECT_NE(ok.out.find("11 stereo frames"), std::string::npos) << ok.out;
  EXPECT_NE(ok.out.find("/ground_truth/odom (nav_msgs/Odometry, 11 poses"), std::string::npos) << ok.out;
  const auto again = run(seq + " " + (tmp / "s.bag"));
  EXPECT_EQ(again.code, 1);
  EXPECT_NE(
      again.out.find("kitti2bag: error: " + (tmp / "s.bag") + ": already exists (use --force to overwrite)"),
      std::string::npos)
      << again.out;
  EXPECT_EQ(run(seq + " " + (tmp / "s.bag") + " --force").code, 0);
}

TEST(Kitti2bagTool, BadInputGivesOneClearLine) {
  binloop::test::TempDir tmp;
  const auto missing = run("/no/such/seq " + (tmp / "x.bag"));
  EXPECT_EQ(missing.code, 1);
  EXPECT_EQ(missing.out, "kitti2bag: error: /no/such/seq: no such folder\n");
  const auto bad_opt = run("a b --frobnicate");
  EXPECT_EQ(bad_opt.code, 2);
  EXPECT_EQ(bad_opt.out, "kitti2bag: unknown option --frobnicate (see kitti2bag --help)\n");
  const auto short_args = run("only_one");
  EXPECT_EQ(short_args.code, 2);
  EXPECT_EQ(short_args.out, "kitti2bag: missing argument <out.bag> (see kitti2bag --help)\n");
}
