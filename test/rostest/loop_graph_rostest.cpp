// Runs under rostest beside a binloop graph (test/rostest/*.test start it from the launch files): plays a bag
// made by kitti2bag from a rendered drive of 1.25 laps round a 50 x 80 m block (one revisit) into the
// graph, switches the loop detector with dynamic_reconfigure on the way, and checks what the graph
// publishes: a LoopClosure near the revisit, the corrected path, the final pose against the ground truth.
// Then it saves the map, resets the graph and loads the map into it (the same keyframes and index, and a
// pair of the start tracked in it again), and sends malformed stereo pairs and checks that the graph says
// so and keeps tracking.
#include <binloop/AddExternalLoop.h>
#include <binloop/Correction.h>
#include <binloop/KeyFrame.h>
#include <binloop/LoadMap.h>
#include <binloop/LocalMapUpdate.h>
#include <binloop/Reset.h>
#include <binloop/SaveMap.h>
#include <dynamic_reconfigure/Reconfigure.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>

#include <filesystem>
#include <fstream>
#include <limits>

#include "binloop/io/map_folder.h"
#include "binloop/io/state_file.h"
#include "binloop/io/trajectory_io.h"
#include "binloop/sim/builtin_route.h"
#include "graph_fixture.h"
#include "rendered_drive.h"
#include "rostest_main.h"
#include "support/test_support.h"

namespace {

using binloop::test::Drive;
using binloop::test::drive;
using binloop::test::firstLapKeyframe;
using binloop::test::Pair;
using binloop::test::readPairs;
using binloop::test::statistics;

class LoopGraph : public binloop::test::GraphTest {};

}  // namespace

TEST_F(LoopGraph, TheRevisitIsClosedTheDetectorSwitchesAndBadPairsAreReported) {
  const Drive& d = drive();
  ASSERT_TRUE(d.problem.empty()) << d.problem;
  const std::vector<Pair> pairs = readPairs(d.bag);
  ASSERT_EQ(pairs.size(), d.route.size());
  ASSERT_TRUE(graphConnected()) << "the Tracking nodelet never subscribed to the stereo topics";

  const size_t lap = static_cast<size_t>(d.route.size() / 1.25), switch_at = 120;
  size_t switched_after_candidates = 0;
  for (size_t i = 0; i < pairs.size(); ++i) {
    if (i == switch_at) {
      dynamic_reconfigure::Reconfigure srv;
      dynamic_reconfigure::StrParameter p;
      p.name = "method";
      p.value = "vladpq";
      srv.request.config.strs.push_back(p);
      ASSERT_TRUE(ros::service::call("/binloop/loop_detector/set_parameters", srv))
          << "dynamic_reconfigure call failed";
      std::lock_guard<std::mutex> lk(seen_.m);
      switched_after_candidates = seen_.candidates.size();
    }
    publishPair(pairs[i].left, pairs[i].right, pairs[i].left_info, pairs[i].right_info);
    const double stamp = pairs[i].left.header.stamp.toSec();
    // Paced by the graph: the next pair goes when this one's pose is out (or after a second).
    waitFor(1.0, [&] { return seen_.poses.count(stamp) > 0; });
  }
  const bool closed = waitFor(30, [&] {
    for (const auto& c : seen_.closures)
      if (c.status == binloop::LoopClosure::ACCEPTED) return true;
    return false;
  });

  std::lock_guard<std::mutex> lk(seen_.m);
  EXPECT_GT(seen_.poses.size(), pairs.size() * 9 / 10) << "poses published for too few pairs";
  ASSERT_TRUE(closed) << "no LoopClosure accepted; " << seen_.closures.size() << " verified";
  for (const auto& c : seen_.closures) {
    if (c.status != binloop::LoopClosure::ACCEPTED) continue;
    EXPECT_GE(c.query_frame, lap - 20) << "a loop accepted before the revisit";
    EXPECT_LT((d.route[c.query_frame].translation() - d.route[c.match_frame].translation()).norm(), 10)
        << "frames " << c.query_frame << " and " << c.match_frame << " are far apart: " << c.detail;
    EXPECT_EQ(c.model, "vladpq") << "the loop came from the model switched away from";
  }
  // The next candidates after the switch come from the new model.
  ASSERT_GT(seen_.candidates.size(), switched_after_candidates);
  EXPECT_EQ(seen_.candidates.back().model, "vladpq");
  bool later_from_new = true;
  for (size_t i = switched_after_candidates + 1; i < seen_.candidates.size(); ++i)
    later_from_new = later_from_new && seen_.candidates[i].model == "vladpq";
  EXPECT_TRUE(later_from_new);
  EXPECT_GT(seen_.corrected_path.poses.size(), 10u) << "no corrected path published";

  // The last pose against the ground truth (the map frame is the first camera's).
  const double last_stamp = pairs.back().left.header.stamp.toSec();
  ASSERT_TRUE(seen_.poses.count(last_stamp)) << "the last pair was not tracked";
  const geometry_msgs::Point& p = seen_.poses[last_stamp].position;
  const Eigen::Vector3d truth = (d.route.front().inverse() * d.route.back()).translation();
  const double err = (Eigen::Vector3d(p.x, p.y, p.z) - truth).norm();
  std::cout << "final pose error " << err << " m; " << seen_.closures.size() << " loops verified\n";
  EXPECT_LT(err, 0.5);

  // Odometry carries its covariances: the pose's known and small (a few cm) on every tracked pair after the
  // first, the twist's on most (unknown only at the start and across a correction).
  ASSERT_GT(seen_.odometry.size(), pairs.size() * 9 / 10);
  size_t pose_known = 0, twist_known = 0;
  double worst_sd = 0;
  for (const auto& o : seen_.odometry) {
    EXPECT_EQ(o.header.frame_id, "odom");
    EXPECT_EQ(o.child_frame_id, "base_link");
    const double var = o.pose.covariance[0] + o.pose.covariance[7] + o.pose.covariance[14];
    if (var > 0 && var < 1) {
      ++pose_known;
      worst_sd = std::max(worst_sd, std::sqrt(var));
    }
    twist_known += o.twist.covariance[0] > 0 && o.twist.covariance[0] < 1e5;
  }
  std::cout << "odometry: pose covariance known on " << pose_known << " of " << seen_.odometry.size()
            << ", twist on " << twist_known << "; largest position sd " << worst_sd << " m\n";
  EXPECT_GE(pose_known, seen_.odometry.size() - 2);
  EXPECT_GE(twist_known, seen_.odometry.size() * 9 / 10);
  EXPECT_LT(worst_sd, 0.2);
  // The camera's pose with its covariance, in the slam frame: one per odometry message, the same position
  // variance (the slam and odom axes differ, the sum over them does not; the lever to base_link is zero
  // here).
  const size_t both = std::min(seen_.poses_with_covariance.size(), seen_.odometry.size());
  ASSERT_GE(both + 2, seen_.odometry.size()) << "fewer poses with covariance than odometry messages";
  for (size_t i = 1; i < both; ++i) {
    const auto& c = seen_.poses_with_covariance[i].pose.covariance;
    const auto& o = seen_.odometry[i].pose.covariance;
    EXPECT_EQ(seen_.poses_with_covariance[i].header.frame_id, "slam");
    EXPECT_NEAR(c[0] + c[7] + c[14], o[0] + o[7] + o[14], 1e-9 + 1e-6 * (o[0] + o[7] + o[14])) << i;
  }
}

// After the first test's drive (or alone, after a short one): save, reset, load into the emptied graph.
TEST_F(LoopGraph, TheMapIsSavedAndLoadedIntoAFreshGraphWithTheSameKeyframesAndIndex) {
  const Drive& d = drive();
  ASSERT_TRUE(d.problem.empty()) << d.problem;
  const std::vector<Pair> pairs = readPairs(d.bag);
  ASSERT_TRUE(graphConnected());
  ASSERT_TRUE(ros::service::waitForService("/binloop/save_map", ros::Duration(30)));
  const auto at_start = statistics();
  auto kfs = at_start.find("local_mapping/keyframes");
  if (kfs == at_start.end() || std::stoi(kfs->second) < 10)  // run alone: map a stretch first
    for (size_t i = 0; i < 80; ++i) {
      publishPair(pairs[i].left, pairs[i].right, pairs[i].left_info, pairs[i].right_info);
      const double stamp = pairs[i].left.header.stamp.toSec();
      waitFor(1.0, [&] { return seen_.poses.count(stamp) > 0; });
    }
  ros::WallDuration(2.0).sleep();  // the last keyframes through mapping and the loop stages
  const auto before = statistics();
  ASSERT_FALSE(before.empty()) << "no /binloop/statistics";
  for (const char* k : {"local_mapping/keyframes", "loop_detector/keyframes", "loop_closing/keyframes"})
    ASSERT_TRUE(before.count(k)) << k;
  EXPECT_GT(std::stoi(before.at("local_mapping/keyframes")), 10);

  binloop::test::TempDir dir;
  binloop::SaveMap save;
  save.request.directory = dir / "map";
  ASSERT_TRUE(ros::service::call("/binloop/save_map", save));
  ASSERT_TRUE(save.response.success) << save.response.message;
  std::cout << "saved: " << save.response.message << "\n";
  EXPECT_NE(save.response.map_id, 0u);
  EXPECT_EQ(
      binloop::checkMapFolder(dir / "map", {"tracking", "local_mapping", "loop_detector", "loop_closing"}),
      save.response.map_id);
  const std::string again_dir = dir / "again";  // a second save of the same graph: another map id
  binloop::SaveMap again;
  again.request.directory = again_dir;
  ASSERT_TRUE(ros::service::call("/binloop/save_map", again));
  ASSERT_TRUE(again.response.success) << again.response.message;
  EXPECT_NE(again.response.map_id, save.response.map_id);

  binloop::Reset reset;
  ASSERT_TRUE(ros::service::call("/binloop/reset", reset));
  ASSERT_TRUE(reset.response.success) << reset.response.message;
  const auto empty = statistics();
  EXPECT_EQ(empty.at("local_mapping/keyframes"), "0");
  EXPECT_EQ(empty.at("loop_detector/keyframes"), "0");
  EXPECT_EQ(empty.at("loop_closing/keyframes"), "0");

  binloop::LoadMap bad;
  bad.request.directory = dir / "nothing";
  ASSERT_TRUE(ros::service::call("/binloop/load_map", bad));
  EXPECT_FALSE(bad.response.success);
  EXPECT_NE(bad.response.message.find("no such state file"), std::string::npos) << bad.response.message;

  // Transactions: a folder whose last stage's file is broken, or that mixes two saves, loads nowhere (before,
  // the stages ahead of the refusal took the new map); a save that cannot replace its folder changes nothing.
  namespace fs = std::filesystem;
  auto refusedEverywhere = [&](const std::string& folder, const std::string& why) {
    binloop::LoadMap l;
    l.request.directory = folder;
    ASSERT_TRUE(ros::service::call("/binloop/load_map", l));
    EXPECT_FALSE(l.response.success);
    EXPECT_NE(l.response.message.find(why), std::string::npos) << l.response.message;
    EXPECT_NE(l.response.message.find("nothing loaded"), std::string::npos) << l.response.message;
    const auto now = statistics();  // as empty as after the reset (tracking: no tracker until a camera comes)
    for (const char* k : {"tracking/keyframes", "local_mapping/keyframes", "loop_detector/keyframes",
                          "loop_closing/keyframes"})
      EXPECT_EQ(now.count(k) ? now.at(k) : "missing", empty.count(k) ? empty.at(k) : "missing")
          << k << " after refusing " << folder;
  };
  fs::copy(dir / "map", dir / "broken");
  fs::resize_file(binloop::stageStatePath(dir / "broken", "loop_closing"), 100);
  refusedEverywhere(dir / "broken", "truncated state file");
  fs::copy(dir / "map", dir / "mixed");
  fs::copy_file(binloop::stageStatePath(again_dir, "loop_detector"),
                binloop::stageStatePath(dir / "mixed", "loop_detector"),
                fs::copy_options::overwrite_existing);
  refusedEverywhere(dir / "mixed", "the folder mixes two saves");
  fs::create_directories(dir / "home");
  std::ofstream(dir / "home/notes.txt") << "mine";
  binloop::SaveMap over;
  over.request.directory = dir / "home";
  ASSERT_TRUE(ros::service::call("/binloop/save_map", over));
  EXPECT_FALSE(over.response.success);
  EXPECT_NE(over.response.message.find("which is not a saved map's"), std::string::npos)
      << over.response.message;
  EXPECT_TRUE(fs::exists(dir / "home/notes.txt"));

  binloop::LoadMap load;
  load.request.directory = dir / "map";
  ASSERT_TRUE(ros::service::call("/binloop/load_map", load));
  ASSERT_TRUE(load.response.success) << load.response.message;
  EXPECT_EQ(load.response.map_id, save.response.map_id);
  std::cout << "loaded: " << load.response.message << "\n";
  const auto after = statistics();
  for (const char* k :
       {"tracking/keyframes", "tracking/map_points", "local_mapping/keyframes", "local_mapping/map_points",
        "loop_detector/model", "loop_detector/keyframes", "loop_detector/index_keyframes",
        "loop_detector/index_bytes", "loop_closing/keyframes", "loop_closing/loops"})
    EXPECT_EQ(after.count(k) ? after.at(k) : "missing", before.count(k) ? before.at(k) : "missing") << k;
  EXPECT_EQ(after.at("tracking/state"), "lost");

  // A pair seen before, later in time: relocalised in the loaded map, where it was. (Without a relocalisation
  // vocabulary, as here, tracking tries the map's most recent keyframes: a pair from the last stretch.)
  const size_t i = pairs.size() - 12;
  Pair p = pairs[i];
  const ros::Time t = pairs.back().left.header.stamp + ros::Duration(50);
  p.left.header.stamp = p.right.header.stamp = p.left_info.header.stamp = p.right_info.header.stamp = t;
  bool placed = false;
  for (int tries = 0; tries < 3 && !placed;
       ++tries) {  // the first may only find the place, the next tracks it
    const ros::Time s = t + ros::Duration(0.1 * tries);
    p.left.header.stamp = p.right.header.stamp = p.left_info.header.stamp = p.right_info.header.stamp = s;
    publishPair(p.left, p.right, p.left_info, p.right_info);
    waitFor(5, [&] { return seen_.poses.count(s.toSec()) > 0; });
    std::lock_guard<std::mutex> lk(seen_.m);
    auto it = seen_.poses.find(s.toSec());
    if (it == seen_.poses.end()) continue;
    const Eigen::Vector3d truth = (d.route.front().inverse() * d.route[i]).translation();
    const geometry_msgs::Point& q = it->second.position;
    const double err = (Eigen::Vector3d(q.x, q.y, q.z) - truth).norm();
    std::cout << "pair " << i << " after the load, try " << tries << ": " << err << " m from the truth\n";
    placed = err < 0.5;
  }
  EXPECT_TRUE(placed) << "a place of the loaded map was not found again";
}

TEST_F(LoopGraph, MalformedPairsAreReportedAndTrackingGoesOn) {
  const Drive& d = drive();
  ASSERT_TRUE(d.problem.empty()) << d.problem;
  const std::vector<Pair> pairs = readPairs(d.bag);
  ASSERT_TRUE(graphConnected());
  // After the other tests, or from the start when run alone: a good pair first, then the bad ones.
  Pair base = pairs.back();
  ros::Time t = base.left.header.stamp + ros::Duration(100);
  auto stamped = [&](Pair p, ros::Time s) {
    p.left.header.stamp = p.right.header.stamp = p.left_info.header.stamp = p.right_info.header.stamp = s;
    return p;
  };
  // The graph may be anywhere after the first test (the load test ends relocalised eleven pairs back), so the
  // first good pair may have to be found from scratch; in the threaded graph one try in about fifty was lost,
  // so it gets three, and a failure says why tracking refused it.
  bool tracked = false;
  for (int tries = 0; tries < 3 && !tracked; ++tries) {
    t = base.left.header.stamp + ros::Duration(100 + tries);
    Pair good = stamped(base, t);
    publishPair(good.left, good.right, good.left_info, good.right_info);
    tracked = waitFor(5, [&] { return seen_.poses.count(t.toSec()) > 0; });
  }
  std::string why = "none reported";
  {
    std::lock_guard<std::mutex> lk(seen_.m);
    if (const std::string v = seen_.tracking("last problem"); !v.empty()) why = v;
  }
  ASSERT_TRUE(tracked) << "a good pair was not tracked in three tries; tracking's last problem: " << why;

  std::vector<Pair> bad;
  Pair p = stamped(base, t + ros::Duration(0.1));
  p.left.encoding = p.right.encoding = "16UC1";  // wrong encoding
  bad.push_back(p);
  p = stamped(base, t + ros::Duration(0.2));
  p.right.width /= 2;  // left and right sizes differ
  p.right.step /= 2;
  bad.push_back(p);
  p = stamped(base, t + ros::Duration(0.3));
  p.left.data.clear();  // empty image
  p.right.data.clear();
  bad.push_back(p);
  bad.push_back(stamped(base, t - ros::Duration(1)));  // stamp out of order
  for (const Pair& b : bad) {
    publishPair(b.left, b.right, b.left_info, b.right_info);
    ros::WallDuration(0.3).sleep();
  }
  // The graph still tracks the next good pair, and its diagnostics count what was dropped.
  const ros::Time t2 = t + ros::Duration(0.5);
  const Pair good = stamped(base, t2);
  publishPair(good.left, good.right, good.left_info, good.right_info);
  EXPECT_TRUE(waitFor(5, [&] { return seen_.poses.count(t2.toSec()) > 0; }))
      << "tracking stopped after bad pairs";
  EXPECT_TRUE(waitFor(5, [&] { return seen_.trackingCount("input dropped") >= 4; }))
      << "diagnostics do not count the dropped pairs";
}

// Run alone on a fresh graph by field_faults.test: the stamps the field sends. One pair stamped at the end of
// ROS's time range (it once ended the manager: converting the pose back threw out of a callback), one a
// million seconds ahead (it once made every later pair "not after the previous one"), and the same pairs
// sent again (a replayed bag: time goes back). The graph stays up, drops the bad pairs with their reason and
// tracks the replay again within a few pairs.
TEST_F(LoopGraph, BadStampsAndAReplayDoNotStopTheGraph) {
  const Drive& d = drive();
  ASSERT_TRUE(d.problem.empty()) << d.problem;
  const std::vector<Pair> pairs = readPairs(d.bag);
  ASSERT_GE(pairs.size(), 60u);
  ASSERT_TRUE(graphConnected());
  auto send = [&](const Pair& p) {
    publishPair(p.left, p.right, p.left_info, p.right_info);
    ros::WallDuration(0.1).sleep();
  };
  auto stamped = [](Pair p, ros::Time s) {
    p.left.header.stamp = p.right.header.stamp = p.left_info.header.stamp = p.right_info.header.stamp = s;
    return p;
  };
  auto posesBetween = [&](double from, double to) {
    std::lock_guard<std::mutex> lk(seen_.m);
    int n = 0;
    for (const auto& [t, pose] : seen_.poses) n += t >= from && t <= to;
    return n;
  };
  for (size_t i = 0; i < 30; ++i) send(pairs[i]);
  send(stamped(pairs[30], ros::Time(4294967295u, 900000000u)));
  for (size_t i = 30; i < 40; ++i) send(pairs[i]);
  send(stamped(pairs[40], pairs[40].left.header.stamp + ros::Duration(1e6)));
  for (size_t i = 40; i < 50; ++i) send(pairs[i]);
  ASSERT_TRUE(waitFor(10, [&] { return seen_.poses.count(pairs[49].left.header.stamp.toSec()) > 0; }))
      << "the last pair before the replay was not tracked";
  const double t0 = pairs[0].left.header.stamp.toSec(), t29 = pairs[29].left.header.stamp.toSec();
  EXPECT_GE(posesBetween(t0, t29), 25);
  EXPECT_GE(posesBetween(pairs[30].left.header.stamp.toSec(), pairs[39].left.header.stamp.toSec()), 9)
      << "pairs after the stamp at the end of ROS's range were not tracked";
  EXPECT_GE(posesBetween(pairs[40].left.header.stamp.toSec(), pairs[49].left.header.stamp.toSec()), 9)
      << "pairs after the stamp a million seconds ahead were not tracked";
  EXPECT_EQ(posesBetween(1e5, 5e9), 0) << "a pose for a bad stamp";

  // The same ten pairs again: three to agree that the clock went back, then relocalised and tracked.
  size_t before = 0;
  {
    std::lock_guard<std::mutex> lk(seen_.m);
    before = seen_.pose_stamps.size();
  }
  for (size_t i = 40; i < 50; ++i) send(pairs[i]);
  EXPECT_TRUE(waitFor(10, [&] { return seen_.pose_stamps.size() >= before + 5; }))
      << "the replayed pairs were not tracked again";
  EXPECT_TRUE(waitFor(5, [&] {
    return seen_.trackingCount("input dropped") >= 4 && seen_.tracking("clock restarts") == "1";
  })) << "diagnostics do not count the dropped pairs and the clock restart";
  // Every stage is still there and answers.
  const auto stats = statistics();
  EXPECT_FALSE(stats.empty()) << "the graph does not answer /binloop/statistics";
}

// Run by field_faults.test after the stamps: stage messages with a NaN in them, sent straight onto the
// graph's own topics (a buggy or hostile node, a corrupted bag). Each stage that takes them drops them,
// counts them and says why; the graph goes on tracking.
TEST_F(LoopGraph, NaNStageMessagesAreDroppedAndSaid) {
  const Drive& d = drive();
  ASSERT_TRUE(d.problem.empty()) << d.problem;
  const std::vector<Pair> pairs = readPairs(d.bag);
  ASSERT_TRUE(graphConnected());
  ros::NodeHandle nh;
  ros::Publisher keyframe = nh.advertise<binloop::KeyFrame>("/binloop/keyframe", 10);
  ros::Publisher refined = nh.advertise<binloop::KeyFrame>("/binloop/refined_keyframe", 10);
  ros::Publisher update = nh.advertise<binloop::LocalMapUpdate>("/binloop/local_map_update", 10);
  ros::Publisher correction = nh.advertise<binloop::Correction>("/binloop/correction", 10);
  // Each stage connects to this node's publishers on its own; give them the time (what did not arrive is
  // reported below).
  waitFor(10, [&] {
    return keyframe.getNumSubscribers() > 0 && refined.getNumSubscribers() > 0 &&
           update.getNumSubscribers() > 0 && correction.getNumSubscribers() > 0;
  });
  ros::WallDuration(2.0).sleep();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  binloop::KeyFrame k;
  k.header.frame_id = "slam";
  k.id = k.state.id = 4000000;
  k.camera.fx = k.camera.fy = 700;
  k.camera.cx = 600;
  k.camera.cy = 180;
  k.camera.baseline_m = 0.5;
  k.camera.width = 1241;
  k.camera.height = 376;
  k.scale_factor = 1.2f;
  k.levels = 8;
  binloop::KeyPoint kp;
  kp.x = static_cast<float>(nan);  // the bad number
  kp.y = 100;
  kp.right_x = kp.depth = -1;
  k.keypoints.push_back(kp);
  k.descriptors.assign(32, 0);
  k.state.point_ids = {0};
  k.state.pose.orientation.w = 1;
  keyframe.publish(k);
  k.revision = 1;
  refined.publish(k);
  binloop::LocalMapUpdate u;
  u.sequence = 1;
  u.keyframe = k.id;
  binloop::MapPoint p;
  p.id = 4000001;
  p.position.x = nan;
  u.points.push_back(p);
  update.publish(u);
  binloop::Correction c;
  c.sequence = 1;
  binloop::KeyframeCorrection kc;
  kc.id = k.id;
  kc.before.orientation.w = nan;
  kc.after.orientation.w = 1;
  c.keyframes.push_back(kc);
  correction.publish(c);

  auto droppedBy = [&](const std::string& stage) {
    for (const auto& [name, values] : seen_.diag) {
      if (name.find(stage) == std::string::npos) continue;
      auto dropped = values.find("input dropped");
      return dropped != values.end() && std::stoi(dropped->second) > 0;
    }
    return false;
  };
  for (const char* stage : {"local mapping", "loop detector", "loop closing", "tracking"})
    EXPECT_TRUE(waitFor(10, [&] { return droppedBy(stage); })) << stage << " did not report the bad message";
  {
    std::lock_guard<std::mutex> lk(seen_.m);
    for (const auto& [name, values] : seen_.diag) {
      auto why = values.find("last problem");
      if (name.find("local mapping") != std::string::npos && why != values.end()) {
        EXPECT_NE(why->second.find("dropped"), std::string::npos) << name << ": " << why->second;
      }
    }
  }
  EXPECT_FALSE(statistics().empty()) << "the graph does not answer /binloop/statistics";
  // Tracking goes on: the drive's next pairs are posed.
  size_t posed = 0;
  for (size_t i = 55; i < 65 && i < pairs.size(); ++i) {
    publishPair(pairs[i].left, pairs[i].right, pairs[i].left_info, pairs[i].right_info);
    const double stamp = pairs[i].left.header.stamp.toSec();
    posed += waitFor(2.0, [&] { return seen_.poses.count(stamp) > 0; });
  }
  EXPECT_GE(posed, 8u) << "tracking stopped after the bad stage messages";
}

// Run alone on a fresh graph by no_camera_info.test (the other .test files leave it out): pairs that come
// without any camera_info wait, then are dropped with the reason; once camera_info comes, tracking starts.
TEST_F(LoopGraph, PairsWithoutCameraInfoAreReportedThenTrackingStarts) {
  const Drive& d = drive();
  ASSERT_TRUE(d.problem.empty()) << d.problem;
  const std::vector<Pair> pairs = readPairs(d.bag);
  ASSERT_TRUE(graphConnected());
  for (size_t i = 0; i < 15; ++i) {  // images only
    left_.publish(pairs[i].left);
    right_.publish(pairs[i].right);
    ros::WallDuration(0.1).sleep();
  }
  EXPECT_TRUE(waitFor(10, [&] {
    return seen_.trackingCount("input dropped") >= 1 &&
           seen_.tracking("last problem").find("no camera_info") != std::string::npos;
  })) << "pairs without camera_info were not reported";
  {
    std::lock_guard<std::mutex> lk(seen_.m);
    EXPECT_TRUE(seen_.poses.empty()) << "a pose without a camera";
  }
  const Pair& p = pairs[20];
  publishPair(p.left, p.right, p.left_info, p.right_info);
  EXPECT_TRUE(waitFor(10, [&] { return seen_.poses.count(p.left.header.stamp.toSec()) > 0; }))
      << "tracking did not start once camera_info came";
}

// Run alone by sim_time_merge.test (one manager, /use_sim_time true, a detector that proposes nothing): the
// drive is played with its own /clock, as `rosbag play --clock` plays a bag, and ends; then a loop is given
// from outside. Its global BA finishes after the clock has stopped, and local mapping merges it on a
// wall-clock timer: on a ROS timer it would wait for a /clock that never comes, so the last global BA of a
// bag was never merged (nor sent to tracking, nor saved).
TEST_F(LoopGraph, AGlobalBaThatFinishesAfterTheBagEndedIsMerged) {
  const Drive& d = drive();
  ASSERT_TRUE(d.problem.empty()) << d.problem;
  const std::vector<Pair> pairs = readPairs(d.bag);
  ASSERT_TRUE(graphConnected());
  ros::NodeHandle nh;
  ros::Publisher clock = nh.advertise<rosgraph_msgs::Clock>("/clock", 10, true);
  for (const Pair& p : pairs) {
    rosgraph_msgs::Clock c;
    c.clock = p.left.header.stamp;
    clock.publish(c);
    publishPair(p.left, p.right, p.left_info, p.right_info);
    const double stamp = p.left.header.stamp.toSec();
    waitFor(1.0, [&] { return seen_.poses.count(stamp) > 0; });
  }
  ros::WallDuration(2.0).sleep();  // the last keyframes through the stages; the clock stands still from here
  std::map<uint64_t, uint64_t> keyframe_at;  // frame -> keyframe id, from the detector's queries
  {
    std::lock_guard<std::mutex> lk(seen_.m);
    for (const auto& c : seen_.candidates) keyframe_at[c.query_frame] = c.query;
    for (const auto& c : seen_.closures)
      ASSERT_NE(c.status, binloop::LoopClosure::ACCEPTED) << "a loop closed before the clock stopped";
  }
  ASSERT_GT(keyframe_at.size(), 20u);
  const auto before = statistics();
  ASSERT_EQ(before.at("local_mapping/corrections"), "0");
  const std::string merged_before = before.at("local_mapping/global_ba_merged");

  // The last keyframe (in the revisit) and the first lap's keyframe nearest to it.
  const auto [query_frame, query] = *keyframe_at.rbegin();
  const auto match = firstLapKeyframe(d, keyframe_at, query_frame, 0);
  const double best = (d.route[match.first].translation() - d.route[query_frame].translation()).norm();
  binloop::AddExternalLoop srv;
  srv.request.query = query;
  srv.request.match = match.second;
  srv.request.source = "rostest";
  ASSERT_TRUE(ros::service::call("/binloop/add_external_loop", srv));
  ASSERT_TRUE(srv.response.accepted) << "frames " << query_frame << " and " << match.first << " (" << best
                                     << " m apart): "
                                     << (srv.response.closures.empty() ? ""
                                                                       : srv.response.closures.back().detail);
  std::map<std::string, std::string> after;
  const bool merged = waitFor(60, [&] {
    after = statistics();
    return after["local_mapping/corrections"] == "1" &&
           std::stoi(after["local_mapping/global_ba_merged"]) > std::stoi(merged_before);
  });
  EXPECT_TRUE(merged) << "with the clock stopped, local mapping applied "
                      << after["local_mapping/corrections"] << " corrections and merged "
                      << after["local_mapping/global_ba_merged"] << " global BAs (" << merged_before
                      << " before the loop)";
}

int main(int argc, char** argv) { return binloop::test::runRostest(argc, argv, "loop_graph_rostest"); }

// Run alone by stage_restarts.test (the split graph with respawn on; the other .test files leave it out):
// each stage's process is killed during the drive and comes back. Local mapping resumes its autosave and
// tracking sends it the keyframes made after it again; to the others local mapping sends the map again (the
// loop stages every keyframe, tracking the whole map to relocalise in), so tracking goes on in the same
// map, and the revisit at the end is still closed against keyframes made before the restarts and applied
// by mapping (the correction sequences agree again).
TEST_F(LoopGraph, RestartedStagesGetTheMapAgainAndTheRevisitIsClosed) {
  const Drive& d = drive();
  ASSERT_TRUE(d.problem.empty()) << d.problem;
  const std::vector<Pair> pairs = readPairs(d.bag);
  ASSERT_TRUE(graphConnected());
  const size_t lap = static_cast<size_t>(d.route.size() / 1.25);
  std::map<double, size_t> index_of;  // a pair's stamp -> its index (tracking counts frames from 0 again)
  for (size_t i = 0; i < pairs.size(); ++i) index_of[pairs[i].left.header.stamp.toSec()] = i;
  struct Restart {
    size_t at;
    const char* stage;
    bool back = false;
    std::string holds;  // what the restarted stage holds once back
  };
  std::vector<Restart> restarts = {{40, "loop_closing"},
                                   {lap / 4, "loop_detector"},
                                   {lap / 2, "local_mapping"},
                                   {lap * 3 / 4, "tracking"}};
  size_t tracked_again_at = 0;  // the first pair with a pose after tracking's restart
  // Local mapping's keyframes when killed and those resumed from its autosave; tracking's counts after.
  std::string mapping_before, resumed, resent, lost_for_good;
  for (size_t i = 0; i < pairs.size(); ++i) {
    if (i == lap / 2 + 20) {  // 20 pairs after local mapping's restart; before tracking's clears its counts
      // Tracking learns of the restart from mapping's next status and says so in its next diagnostics,
      // which under load can come after these 20 pairs: wait for counts that cover what mapping held
      // (the bound below still fails when they never do).
      // The counts the checks after the run judge, read again on every try.
      const auto read_counts = [&] {
        resent = seen_.tracking("keyframes sent again (mapping restarted)");
        lost_for_good = seen_.tracking("keyframes mapping lost for good");
        resumed = statistics()["local_mapping/resumed_keyframes"];
      };
      waitFor(20, [&] {
        read_counts();
        return !resent.empty() && !resumed.empty() && !mapping_before.empty() &&
               std::stol(resumed) + std::stol(resent) >= std::stol(mapping_before);
      });
      std::cout << "local mapping held " << mapping_before << " keyframes when killed, resumed " << resumed
                << "; tracking sent " << resent << " again (" << lost_for_good << " no longer kept)\n";
    }
    for (Restart& r : restarts) {
      if (i != r.at) continue;
      if (std::string(r.stage) == "local_mapping") mapping_before = statistics()["local_mapping/keyframes"];
      const std::string node = std::string("/binloop/") + r.stage;
      ASSERT_EQ(binloop::test::runCommand("rosnode kill " + node).code, 0) << "could not kill " << node;
      const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(60);
      ros::WallDuration(2.0).sleep();
      while (!r.back && ros::WallTime::now() < until) {
        const auto s = statistics();
        auto mine = s.find(std::string(r.stage) + "/keyframes"), mapping = s.find("local_mapping/keyframes");
        if (std::string(r.stage) == "local_mapping") {
          // Back when it answers with the map of its autosave (an empty one would hold none).
          r.back = mapping != s.end() && std::stoi(mapping->second) > 0;
          r.holds =
              r.back ? mapping->second + " keyframes (its autosave, then those tracking sent again)" : "";
        } else if (std::string(r.stage) == "tracking") {
          // Back when it takes pairs again (its map comes with its camera, at the next pair).
          r.back =
              s.count("tracking/frames") && left_.getNumSubscribers() > 0 && right_.getNumSubscribers() > 0;
          if (r.back) ros::WallDuration(1.0).sleep();  // local mapping's map reaches it
          r.holds = "-";
        } else if (mine != s.end() && mapping != s.end() && std::stoi(mapping->second) > 5 &&
                   std::stoi(mine->second) >= std::stoi(mapping->second)) {
          r.back = true;
          r.holds = mine->second + " of " + mapping->second + " keyframes";
        }
        ros::WallDuration(0.5).sleep();
      }
      EXPECT_TRUE(r.back) << r.stage << " did not come back";
      std::cout << r.stage << " restarted at pair " << i << ": holds " << r.holds << "\n";
    }
    publishPair(pairs[i].left, pairs[i].right, pairs[i].left_info, pairs[i].right_info);
    const double stamp = pairs[i].left.header.stamp.toSec();
    const bool posed = waitFor(1.0, [&] { return seen_.poses.count(stamp) > 0; });
    if (posed && i > restarts.back().at && !tracked_again_at) tracked_again_at = i;
  }
  const size_t restarted_at = restarts.back().at;
  EXPECT_TRUE(tracked_again_at > 0 && tracked_again_at <= restarted_at + 10)
      << "tracking posed no pair within 10 of its restart (first: " << tracked_again_at << ")";
  {
    // In the same map: after the restart the poses are where the car is, not at a new map's origin.
    std::lock_guard<std::mutex> lk(seen_.m);
    int near = 0, posed = 0;
    for (size_t i = restarted_at; i < restarted_at + 30 && i < pairs.size(); ++i) {
      auto it = seen_.poses.find(pairs[i].left.header.stamp.toSec());
      if (it == seen_.poses.end()) continue;
      ++posed;
      const Eigen::Vector3d truth = (d.route.front().inverse() * d.route[i]).translation();
      const geometry_msgs::Point& q = it->second.position;
      near += (Eigen::Vector3d(q.x, q.y, q.z) - truth).norm() < 2.0;
    }
    EXPECT_GE(posed, 20);
    EXPECT_EQ(near, posed) << "poses after tracking's restart are not in the map it had";
  }
  const bool closed = waitFor(60, [&] {
    for (const auto& c : seen_.closures)
      if (c.status == binloop::LoopClosure::ACCEPTED) return true;
    return false;
  });
  ASSERT_TRUE(closed) << "no loop accepted after the restarts";
  {
    // Every accepted loop is true; one at least reaches a keyframe made before the first restart (the
    // revisit runs over the first quarter lap, so later loops may match keyframes made after it).
    std::lock_guard<std::mutex> lk(seen_.m);
    std::string matches;
    bool reaches_back = false;
    for (const auto& c : seen_.closures) {
      if (c.status != binloop::LoopClosure::ACCEPTED) continue;
      reaches_back |= c.match_frame < restarts.front().at;
      auto q = index_of.find(c.header.stamp.toSec());
      ASSERT_NE(q, index_of.end());
      matches += " " + std::to_string(q->second) + "->" + std::to_string(c.match_frame);
      EXPECT_LT((d.route[q->second].translation() - d.route[c.match_frame].translation()).norm(), 10)
          << "loop " << q->second << " -> " << c.match_frame;
    }
    EXPECT_TRUE(reaches_back) << "no loop reaches keyframes made before the restarts (pair "
                              << restarts.front().at << "); accepted:" << matches;
    std::cout << "loops accepted (pair -> matched pair):" << matches << "\n";
  }
  // Nothing local mapping lacked after its restart was lost: what its autosave lacked, tracking sent again
  // (none when the save was of the last keyframe; more than it held when it had culled some since).
  ASSERT_FALSE(resumed.empty() || resent.empty() || mapping_before.empty());
  EXPECT_GT(std::stol(resumed), 0);
  EXPECT_GE(std::stol(resumed) + std::stol(resent), std::stol(mapping_before));
  EXPECT_EQ(lost_for_good, "0");
  // Mapping applied it: its correction count follows loop closing's.
  bool applied = false;
  for (int tries = 0; tries < 60 && !applied; ++tries, ros::WallDuration(0.5).sleep()) {
    const auto s = statistics();
    applied = s.count("local_mapping/corrections") && std::stoi(s.at("local_mapping/corrections")) >= 1 &&
              s.at("local_mapping/corrections") == s.at("loop_closing/corrections");
  }
  const auto s = statistics();
  EXPECT_TRUE(applied) << "mapping applied "
                       << (s.count("local_mapping/corrections") ? s.at("local_mapping/corrections") : "?")
                       << " corrections, loop closing made "
                       << (s.count("loop_closing/corrections") ? s.at("loop_closing/corrections") : "?");
}

// Run alone by mapping_down.test (the split graph, no respawn; the other .test files leave it out): local
// mapping's process dies mid-drive. Tracking does not wait on it: the keyframes in flight are given up as
// soon as nothing subscribes to them, it goes on making keyframes into its own map and posing every pair, and
// its diagnostics say what it gave up.
TEST_F(LoopGraph, TrackingGoesOnWhenLocalMappingIsGone) {
  const Drive& d = drive();
  ASSERT_TRUE(d.problem.empty()) << d.problem;
  const std::vector<Pair> pairs = readPairs(d.bag);
  ASSERT_TRUE(graphConnected());
  const size_t down_at = 60, until = 160;
  size_t posed_after = 0;
  for (size_t i = 0; i < until; ++i) {
    if (i == down_at) {
      ASSERT_EQ(binloop::test::runCommand("rosnode kill /binloop/local_mapping").code, 0);
      ros::WallDuration(1.0).sleep();
    }
    publishPair(pairs[i].left, pairs[i].right, pairs[i].left_info, pairs[i].right_info);
    const double stamp = pairs[i].left.header.stamp.toSec();
    const bool posed = waitFor(1.0, [&] { return seen_.poses.count(stamp) > 0; });
    if (i >= down_at && posed) ++posed_after;
    ros::WallDuration(0.05).sleep();  // about ten pairs a second
  }
  EXPECT_GE(posed_after, (until - down_at) * 9 / 10) << "tracking stopped posing pairs without local mapping";
  EXPECT_TRUE(waitFor(5, [&] {
    return seen_.trackingCount("keyframes given up (mapping did not answer)") > 0;
  })) << "tracking's diagnostics do not say that keyframes were given up";
}
