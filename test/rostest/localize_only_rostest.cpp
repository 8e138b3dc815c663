// Runs under rostest beside kitti_stereo.launch with localize_only:=true (localize_only.test): a map of the
// drive's first lap, made offline by `run --save-map`, is loaded with /binloop/load_map, then the revisit
// (the quarter lap after it, over the start) is sent. Checks that every pair is placed where the car is and
// that no stage's map grows.
#include <binloop/LoadMap.h>

#include "graph_fixture.h"
#include "rendered_drive.h"
#include "rostest_main.h"
#include "support/test_support.h"

namespace {

using binloop::test::Drive;
using binloop::test::drive;
using binloop::test::Pair;
using binloop::test::readPairs;
using binloop::test::statistics;

class LocalizeOnly : public binloop::test::GraphTest {};

TEST_F(LocalizeOnly, TheRevisitIsTrackedInTheLoadedMapAndNoStageAddsToIt) {
  const Drive& d = drive();
  ASSERT_TRUE(d.problem.empty()) << d.problem;
  const std::vector<Pair> pairs = readPairs(d.bag);
  ASSERT_EQ(pairs.size(), d.route.size());
  const size_t lap = static_cast<size_t>(d.route.size() / 1.25);
  binloop::test::TempDir dir;
  const auto mapped = binloop::test::runCommand(std::string(BINLOOP_TOOL_DIR) + "/run " + (*d.dir / "seq") +
                                                " --lockstep --end " + std::to_string(lap) + " --out " +
                                                (dir / "first_lap") + " --save-map " + (dir / "map"));
  ASSERT_EQ(mapped.code, 0) << mapped.out;
  ASSERT_TRUE(graphConnected());
  ASSERT_TRUE(ros::service::waitForService("/binloop/load_map", ros::Duration(30)));
  binloop::LoadMap load;
  load.request.directory = dir / "map";
  ASSERT_TRUE(ros::service::call("/binloop/load_map", load));
  ASSERT_TRUE(load.response.success) << load.response.message;
  std::cout << "loaded: " << load.response.message << "\n";
  const auto before = statistics();
  ASSERT_TRUE(before.count("local_mapping/keyframes"));
  EXPECT_GT(std::stoi(before.at("local_mapping/keyframes")), 20);

  size_t posed = 0, near = 0;
  double worst = 0;
  for (size_t i = lap; i < pairs.size(); ++i) {
    publishPair(pairs[i].left, pairs[i].right, pairs[i].left_info, pairs[i].right_info);
    const double stamp = pairs[i].left.header.stamp.toSec();
    if (!waitFor(2.0, [&] { return seen_.poses.count(stamp) > 0; })) continue;
    std::lock_guard<std::mutex> lk(seen_.m);
    const geometry_msgs::Point& q = seen_.poses[stamp].position;
    const double err =
        (Eigen::Vector3d(q.x, q.y, q.z) - (d.route.front().inverse() * d.route[i]).translation()).norm();
    ++posed;
    near += err < 0.3;
    worst = std::max(worst, err);
  }
  const size_t sent = pairs.size() - lap;
  std::cout << posed << " of " << sent << " pairs posed, " << near << " within 0.3 m; worst " << worst
            << " m\n";
  EXPECT_GE(posed, sent * 9 / 10) << "too few pairs tracked in the loaded map";
  EXPECT_GE(near + 2, posed) << "poses away from where the car is";
  ros::WallDuration(2.0).sleep();  // anything a stage would still add
  const auto after = statistics();
  for (const char* k : {"tracking/keyframes", "local_mapping/keyframes", "local_mapping/map_points",
                        "loop_detector/keyframes", "loop_closing/keyframes"})
    EXPECT_EQ(after.count(k) ? after.at(k) : "missing", before.count(k) ? before.at(k) : "missing") << k;
  EXPECT_EQ(after.at("tracking/state"), "ok");
  std::lock_guard<std::mutex> lk(seen_.m);
  EXPECT_TRUE(seen_.closures.empty()) << "a loop verified without any new keyframe";
}

}  // namespace

int main(int argc, char** argv) { return binloop::test::runRostest(argc, argv, "localize_only_rostest"); }
