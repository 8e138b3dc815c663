// Runs under rostest beside stereo_camera.launch (stereo_camera_bag.test: the live-camera launch file with
// its defaults, every shadow model on): the rendered drive is played with `rosbag play` as raw image and
// camera_info topics in stereo_image_proc's layout, stamped as a camera stamps them, with no /clock. Checks
// that the graph tracks the drive and closes its revisit with the default model, that every shadow model with
// a file publishes its own candidates for every keyframe, and that add_external_loop verifies a loop given
// from outside like a detected one: a true pair accepted, a pair 40 m apart refused, an unknown keyframe
// named.
#include <binloop/AddExternalLoop.h>

#include <algorithm>
#include <set>

#include "binloop/map/ids.h"
#include "binloop/pipeline/model_files.h"
#include "graph_fixture.h"
#include "rendered_drive.h"
#include "rostest_main.h"
#include "support/test_support.h"

namespace {

using binloop::test::Drive;
using binloop::test::drive;
using binloop::test::firstLapKeyframe;

class CameraBag : public binloop::test::GraphTest {
 protected:
  void SetUp() override {
    GraphTest::SetUp();
    ros::NodeHandle nh;
    shadow_models_ = binloop::shadowModelNames("all", "hmvlad", BINLOOP_ROOT_DIR "/vocab/kitti08");
    for (const std::string& m : shadow_models_)
      subs_.push_back(nh.subscribe<binloop::LoopCandidates>("/binloop/shadow/" + m + "/loop_candidates", 1000,
                                                            [this](const auto& c) {
                                                              std::lock_guard<std::mutex> lk(seen_.m);
                                                              shadow_[c->model].push_back(*c);
                                                            }));
  }

  /// Plays the drive's bag once, as a camera driver would publish it (no /clock), after the graph is up.
  void playDrive() {
    const Drive& d = drive();
    ASSERT_TRUE(d.problem.empty()) << d.problem;
    ASSERT_TRUE(graphConnected()) << "the Tracking nodelet never subscribed to the stereo topics";
    ros::WallDuration(1.0).sleep();  // the shadow subscriptions connect
    const auto r = binloop::test::runCommand("rosbag play -q -d 1 " + d.bag);
    ASSERT_EQ(r.code, 0) << r.out;
    waitFor(30, [&] {
      for (const auto& c : seen_.closures)
        if (c.status == binloop::LoopClosure::ACCEPTED) return true;
      return false;
    });
    ros::WallDuration(2.0).sleep();  // the last keyframes through the loop stages
    std::lock_guard<std::mutex> lk(seen_.m);
    for (const auto& c : seen_.candidates) keyframe_at_[c.query_frame] = c.query;
  }

  /// The drive's keyframes, frame -> keyframe id, from the active model's queries (one per keyframe); a
  /// member of the suite, kept across its tests as the graph is.
  inline static std::map<uint64_t, uint64_t> keyframe_at_;

  std::vector<std::string> shadow_models_;
  std::map<std::string, std::vector<binloop::LoopCandidates>> shadow_;  // by model, under seen_.m
};

TEST_F(CameraBag, ABagOfRawTopicsIsTrackedItsRevisitClosedAndEveryShadowModelPublished) {
  playDrive();
  if (HasFatalFailure()) return;
  const Drive& d = drive();
  const size_t lap = static_cast<size_t>(d.route.size() / 1.25);
  std::lock_guard<std::mutex> lk(seen_.m);
  std::cout << seen_.poses.size() << " poses of " << d.route.size() << " pairs; " << seen_.closures.size()
            << " loops verified; " << seen_.candidates.size() << " keyframes queried\n";
  EXPECT_GE(seen_.poses.size(), d.route.size() * 9 / 10) << "poses published for too few pairs";
  size_t accepted = 0;
  for (const auto& c : seen_.closures) {
    if (c.status != binloop::LoopClosure::ACCEPTED) continue;
    ++accepted;
    EXPECT_GE(c.query_frame, lap - 20) << "a loop accepted before the revisit";
    EXPECT_LT((d.route[c.query_frame].translation() - d.route[c.match_frame].translation()).norm(), 10)
        << "frames " << c.query_frame << " and " << c.match_frame << " are far apart: " << c.detail;
    EXPECT_EQ(c.model, "hmvlad") << "not the launch file's default model";
  }
  EXPECT_GE(accepted, 1u) << "the revisit was not closed";
  // The last pose against the ground truth (the slam frame is the first camera's).
  ASSERT_FALSE(seen_.poses.empty());
  const geometry_msgs::Point& p = seen_.poses.rbegin()->second.position;
  const Eigen::Vector3d truth = (d.route.front().inverse() * d.route.back()).translation();
  const double err = (Eigen::Vector3d(p.x, p.y, p.z) - truth).norm();
  std::cout << "final pose error " << err << " m\n";
  EXPECT_LT(err, 0.5);

  // Shadow models: each with a file answers every keyframe the active model answers, on its own topic, marked
  // as a shadow; the active model's topic carries only the active model.
  ASSERT_FALSE(seen_.candidates.empty());
  for (const auto& c : seen_.candidates) EXPECT_EQ(c.model, "hmvlad");
  EXPECT_GE(shadow_models_.size(), 3u) << "the package ships fabmap, vlad and vladpq";
  for (const std::string& m : shadow_models_) {
    const auto& got = shadow_[m];
    std::cout << "shadow " << m << ": " << got.size() << " keyframes\n";
    EXPECT_GE(got.size() + 2, seen_.candidates.size()) << m << " answered too few keyframes";
    size_t found = 0;
    for (const auto& c : got) {
      EXPECT_TRUE(c.shadow) << m;
      EXPECT_EQ(c.model, m);
      found += !c.candidates.empty();
    }
    EXPECT_GT(found, 0u) << m << " never proposed a candidate";
  }
}

// After the drive (or after playing it, when run alone): loops handed to loop closing from outside.
TEST_F(CameraBag, AnExternalLoopIsVerifiedLikeADetectedOne) {
  if (keyframe_at_.empty()) playDrive();  // run alone
  if (HasFatalFailure()) return;
  const Drive& d = drive();
  const size_t lap = static_cast<size_t>(d.route.size() / 1.25);
  ASSERT_TRUE(ros::service::waitForService("/binloop/add_external_loop", ros::Duration(10)));
  const std::map<uint64_t, uint64_t>& keyframe_at = keyframe_at_;
  ASSERT_GT(keyframe_at.size(), 20u);
  const auto [query_frame, query] =
      *keyframe_at.rbegin();  // the last keyframe, a quarter lap into the revisit
  ASSERT_GE(query_frame, lap);
  auto call = [](uint64_t q, uint64_t m) {
    binloop::AddExternalLoop srv;
    srv.request.query = q;
    srv.request.match = m;
    srv.request.source = "rostest";
    EXPECT_TRUE(ros::service::call("/binloop/add_external_loop", srv));
    return srv.response;
  };
  const auto [near_frame, near] = firstLapKeyframe(d, keyframe_at, query_frame, 0);
  const auto good = call(query, near);
  ASSERT_FALSE(good.closures.empty());
  std::cout << "keyframes " << query << " and " << near << ", frames " << query_frame << " and " << near_frame
            << ": " << good.closures.back().status << ", " << good.closures.back().detail << "\n";
  EXPECT_TRUE(good.accepted) << good.closures.back().status << ": " << good.closures.back().detail;
  EXPECT_EQ(good.closures.back().model, "rostest");
  // Re-anchoring (loop_closing.reanchor_min_m, 5 m): when the asked keyframe lies further from the query,
  // the loop is measured against a covisible keyframe of it that lies nearer, and the closure names that
  // keyframe's frame. Whether it happens depends on where the threaded run put its keyframes.
  const std::string& detail = good.closures.back().detail;
  const std::string anchored = "anchored at keyframe ";
  if (const size_t at = detail.find(anchored); at == std::string::npos) {
    EXPECT_EQ(good.closures.back().match_frame, near_frame);
  } else {
    const uint64_t anchor = std::stoull(detail.substr(at + anchored.size()));
    const auto named = std::find_if(keyframe_at.begin(), keyframe_at.end(),
                                    [&](const auto& e) { return binloop::counterOf(e.second) == anchor; });
    ASSERT_NE(named, keyframe_at.end()) << "keyframe " << anchor << " was never queried: " << detail;
    EXPECT_EQ(good.closures.back().match_frame, named->first) << detail;
    auto metres = [&](uint64_t frame) {
      return (d.route[frame].translation() - d.route[query_frame].translation()).norm();
    };
    EXPECT_LT(metres(named->first), metres(near_frame)) << "re-anchored further from the query: " << detail;
  }

  const auto [far_frame, far] = firstLapKeyframe(d, keyframe_at, query_frame, 40);
  const auto wrong = call(query, far);
  ASSERT_FALSE(wrong.closures.empty());
  std::cout << "frames " << query_frame << " and " << far_frame << ": " << wrong.closures.back().status
            << "\n";
  EXPECT_FALSE(wrong.accepted)
      << "a loop between places "
      << (d.route[far_frame].translation() - d.route[query_frame].translation()).norm()
      << " m apart was accepted";
  EXPECT_NE(wrong.closures.back().status, binloop::LoopClosure::ACCEPTED);

  const auto unknown = call(query, 987654321);
  EXPECT_FALSE(unknown.accepted);
  ASSERT_FALSE(unknown.closures.empty());
  EXPECT_EQ(unknown.closures.back().status, binloop::LoopClosure::UNKNOWN_KEYFRAME);
}

}  // namespace

int main(int argc, char** argv) { return binloop::test::runRostest(argc, argv, "camera_bag_rostest"); }
