// run-bag as a user runs it: a bag of compressed images (what image_transport records on a robot) with
// transport:=compressed, the inputs moved by the stereo namespace argument, and every shipped model closing
// the loop of a rendered drive through `rosbag play`.
#include "binloop/io/trajectory_io.h"
#include "binloop/sim/builtin_route.h"
#include "support/test_support.h"

namespace {
/// `scripts/binloop run-bag <bag> --out <out> <args>` with its own master on `port`, so that no other
/// master on the machine is used.
binloop::test::CommandResult runBag(const std::string& bag, const std::string& out, const std::string& args,
                                    int port) {
  return binloop::test::runCommand("export ROS_MASTER_URI=http://localhost:" + std::to_string(port) + " && " +
                                   std::string(BINLOOP_ROOT_DIR) + "/scripts/binloop run-bag " + bag +
                                   " --out " + out + " " + args);
}
}  // namespace

TEST(RunBag, ABagOfCompressedImagesIsTrackedWithTransportCompressed) {
  const std::string seq = binloop::test::sharedData("kitti/sample_00");
  BINLOOP_REQUIRE_DATA(seq);
  binloop::test::TempDir tmp;
  const auto bag = binloop::test::runCommand(std::string(BINLOOP_TOOL_DIR) + "/kitti2bag " + seq + " " +
                                             (tmp / "png.bag") + " --png");
  ASSERT_EQ(bag.code, 0) << bag.out;
  const auto r = runBag(tmp / "png.bag", tmp / "out", "--launch-args transport:=compressed", 11392);
  ASSERT_EQ(r.code, 0) << r.out;
  const std::string summary = binloop::test::readText(tmp / "out/summary.json");
  EXPECT_NE(summary.find("\"frames\": 11,"), std::string::npos)
      << summary << "\n"
      << binloop::test::readText(tmp / "out/graph.log");
  EXPECT_NE(summary.find("\"lost_frames\": 0,"), std::string::npos) << summary;
}

// ~stereo moves the inputs: a graph told to listen under another namespace takes none of the bag's pairs,
// and says where it listens.
TEST(RunBag, TheStereoNamespaceArgumentMovesTheInputs) {
  const std::string seq = binloop::test::sharedData("kitti/sample_00");
  BINLOOP_REQUIRE_DATA(seq);
  binloop::test::TempDir tmp;
  const auto bag = binloop::test::runCommand(std::string(BINLOOP_TOOL_DIR) + "/kitti2bag " + seq + " " +
                                             (tmp / "raw.bag") + " --end 3");
  ASSERT_EQ(bag.code, 0) << bag.out;
  const auto r = runBag(tmp / "raw.bag", tmp / "out", "--launch-args stereo:=/elsewhere", 11393);
  ASSERT_EQ(r.code, 0) << r.out;
  const std::string log = binloop::test::readText(tmp / "out/graph.log");
  EXPECT_NE(log.find("sync on /elsewhere/left/image_rect + /elsewhere/right/image_rect"), std::string::npos)
      << log;
  EXPECT_NE(binloop::test::readText(tmp / "out/summary.json").find("\"frames\": 0,"), std::string::npos);
}

// Every shipped model through the whole graph as users run it (`rosbag play` of the rostests' rendered loop
// drive at 2x, run-bag's recorder): the one revisit is closed. hmvlad, the default, is played by
// InstalledPackage.TheLaunchFileWithItsDefaultsClosesTheLoopOfABag.
class RunBagModels : public ::testing::TestWithParam<const char*> {};

TEST_P(RunBagModels, TheRenderedLoopIsClosed) {
  static binloop::test::TempDir dir;
  static const std::string bag = [] {
    binloop::writeKittiPoses(dir / "route.txt", binloop::sim::loopRoute(50, 80, 12, 8, 10, 1.25));
    const std::string tools = BINLOOP_TOOL_DIR;
    const auto render = binloop::test::runCommand(tools + "/render --route " + (dir / "route.txt") +
                                                  " --calib kitti04 --out " + (dir / "seq"));
    const auto bag =
        binloop::test::runCommand(tools + "/kitti2bag " + (dir / "seq") + " " + (dir / "drive.bag"));
    return render.code == 0 && bag.code == 0 ? dir / "drive.bag" : std::string();
  }();
  ASSERT_FALSE(bag.empty()) << "the drive could not be rendered into a bag";
  const std::string model = GetParam();
  binloop::test::TempDir tmp;
  const auto r = runBag(bag, tmp / "out", "--rate 2 --detector " + model, 11394);
  ASSERT_EQ(r.code, 0) << r.out;
  const std::string summary = binloop::test::readText(tmp / "out/summary.json");
  const auto at = summary.find("\"accepted\": ");
  ASSERT_NE(at, std::string::npos) << model << " accepted no loop:\n" << summary;
  EXPECT_GE(std::stoi(summary.substr(at + 12)), 1) << summary;
  EXPECT_NE(binloop::test::readText(tmp / "out/loops.csv").find("," + model + ",0,"), std::string::npos);
}

INSTANTIATE_TEST_SUITE_P(Shipped, RunBagModels, ::testing::Values("vlad", "vladpq", "fabmap"));
