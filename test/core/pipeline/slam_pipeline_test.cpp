// The SLAM stages end to end: real KITTI frames, a rendered stretch of route 06 (rendered here, in memory),
// lock-step determinism, threaded mode, and bad input that must not stop tracking.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <limits>
#include <map>
#include <set>
#include <tuple>

#include <opencv2/imgproc.hpp>
#include "binloop/eval/trajectory_metrics.h"
#include "binloop/io/kitti_sequence.h"
#include "binloop/io/state_file.h"
#include "binloop/io/trajectory_io.h"
#include "binloop/mapping/local_mapper.h"
#include "binloop/pipeline/slam_pipeline.h"
#include "binloop/place/hbow_recognizer.h"
#include "binloop/sim/stereo_renderer.h"
#include "binloop/sim/texture_bank.h"
#include "binloop/tracking/tracking_stage.h"

#include "covariance_check.h"
#include "small_vocabulary.h"
#include "support/test_support.h"

using namespace binloop;

namespace {

// Frames first..first+n-1 of KITTI route 06 rendered as the `render` tool does (kitti04 camera, seed 1): by
// default with its road texture that repeats every 8 m, or as `render --aperiodic-ground`. frames[k] shows
// route[first + k].
struct RenderedStretch {
  std::vector<Pose3> route;
  std::vector<StereoFrame> frames;
  int first = 0;
  StereoCamera cam = kittiCameraByName("kitti04");
};

const RenderedStretch* renderedStretch(int n, bool aperiodic_ground = false, int first = 0) {
  static std::map<std::tuple<int, bool, int>, RenderedStretch> cache;
  auto it = cache.find({n, aperiodic_ground, first});
  if (it != cache.end()) return &it->second;
  const std::string poses = test::sharedData("kitti/poses/06.txt");
  if (!std::filesystem::exists(poses)) return nullptr;
  RenderedStretch& s = cache[{n, aperiodic_ground, first}];
  s.route = readKittiPoses(poses);
  s.first = first;
  sim::WorldParams wp;
  wp.aperiodic_ground = aperiodic_ground;
  const auto world =
      sim::World::build(s.route, sim::TextureBank::build(sim::defaultTexturePhotos(), 1), wp, 1);
  sim::StereoRenderer r(world, s.cam, {}, 1);
  s.frames = sim::renderFrames(r, s.route, static_cast<size_t>(first), static_cast<size_t>(n));
  return &s;
}

std::vector<msg::TrackedFrame> runOn(const std::vector<StereoFrame>& frames, const StereoCamera& cam,
                                     const PipelineParams& pp, std::vector<Pose3>* final_poses = nullptr,
                                     const TrackerParams& tp = {}) {
  SlamPipeline slam(cam, tp, {}, pp);
  std::vector<msg::TrackedFrame> out;
  for (const auto& f : frames) out.push_back(slam.process(f));
  slam.finish();
  if (final_poses) {
    for (const auto& tf : out) {
      Pose3 T_ref;
      final_poses->push_back(tf.reference != kNoId && slam.mapper().keyframePose(tf.reference, &T_ref)
                                 ? Pose3(T_ref * tf.T_ref_c)
                                 : tf.T_w_c);
    }
  }
  return out;
}

}  // namespace

// Real images. The sample's ground truth moves 0.86 m per frame, but two independent estimates from its
// images (binloop's, and OpenCV's SGBM + ORB + solvePnPRansac) agree on 0.66-0.74 m for the first frames and
// on about twice the rotation; the bounds below are what the images support (see docs/slam.md).
TEST(SlamPipeline, RealKittiSampleIsTrackedThroughout) {
  const std::string dir = test::sharedData("kitti/sample_00");
  BINLOOP_REQUIRE_DATA(dir);
  const KittiSequence seq = KittiSequence::open(dir);
  std::vector<StereoFrame> frames;
  for (size_t i = 0; i < seq.size(); ++i) frames.push_back(seq.load(i));
  std::vector<Pose3> poses;
  const auto tracked = runOn(frames, seq.camera(), PipelineMode::kLockStep, &poses);
  ASSERT_EQ(tracked.size(), 11u);
  for (const auto& tf : tracked)
    EXPECT_EQ(tf.state, msg::TrackingState::kOk) << "frame " << tf.frame_index << ": " << tf.problem;
  const Pose3 err = seq.poses().back().inverse() * poses.back();
  const double travelled = seq.poses().back().translation().norm();
  EXPECT_LT(err.translation().norm(), 0.2 * travelled) << "last pose " << err.translation().transpose();
  EXPECT_LT(rotationDeg(err.linear()), 1.5);
  // Forward, as the car drives, by most of the ground truth's distance.
  EXPECT_GT(poses.back().translation().z(), 0.75 * travelled);
}

TEST(SlamPipeline, RenderedRoute06StretchIsTrackedWithLowDrift) {
  const RenderedStretch* s = renderedStretch(300);
  if (!s) GTEST_SKIP() << "needs " << test::sharedData("kitti/poses/06.txt");
  std::vector<Pose3> poses;
  const auto tracked = runOn(s->frames, s->cam, PipelineMode::kLockStep, &poses);
  for (const auto& tf : tracked)
    ASSERT_EQ(tf.state, msg::TrackingState::kOk) << "frame " << tf.frame_index << ": " << tf.problem;
  // What each keyframe decision weighed: in lock-step nothing waits for mapping, and once a second keyframe
  // is mapped the reference holds points other keyframes see (about 300-500 here; with one keyframe, none).
  size_t second = 1;
  while (second < tracked.size() && tracked[second].new_keyframe == kNoId) ++second;
  ASSERT_LT(second, 20u);
  for (size_t i = 1; i < tracked.size(); ++i) {
    EXPECT_EQ(tracked[i].mapping_queue, 0) << "frame " << i;
    if (i > second) {
      EXPECT_GT(tracked[i].reference_points, 100) << "frame " << i;
    }
  }
  MatchedPoses m;
  for (size_t i = 0; i < poses.size(); ++i) {
    m.frames.push_back(static_cast<int>(i));
    m.gt.push_back(s->route[i]);
    m.est.push_back(poses[i]);
  }
  m.gt_frames = poses.size();
  const TrajectoryMetrics r = evaluateTrajectory(m);
  // Measured: ATE 0.15 m and t_rel 0.31 % over 200 frames; the bounds leave room without hiding a failure.
  EXPECT_LT(r.ate_rmse_m, 0.6);
  ASSERT_TRUE(r.relative.valid) << r.relative.reason;
  EXPECT_LT(r.relative.t_rel_pct, 1.0);
  EXPECT_LT(r.relative.r_rel_deg_per_100m, 0.6);
}

TEST(SlamPipeline, LockStepRunsAreBitIdentical) {
  const RenderedStretch* s = renderedStretch(300);
  if (!s) GTEST_SKIP() << "needs " << test::sharedData("kitti/poses/06.txt");
  const std::vector<StereoFrame> frames(s->frames.begin(), s->frames.begin() + 80);
  std::vector<Pose3> a, b;
  runOn(frames, s->cam, PipelineMode::kLockStep, &a);
  runOn(frames, s->cam, PipelineMode::kLockStep, &b);
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i)
    ASSERT_TRUE(a[i].matrix() == b[i].matrix()) << "frame " << i << " differs";
}

TEST(SlamPipeline, ThreadedModeTracksTheSameStretch) {
  const RenderedStretch* s = renderedStretch(300);
  if (!s) GTEST_SKIP() << "needs " << test::sharedData("kitti/poses/06.txt");
  const std::vector<StereoFrame> frames(s->frames.begin(), s->frames.begin() + 150);
  std::vector<Pose3> poses;
  const auto tracked = runOn(frames, s->cam, PipelineMode::kThreaded, &poses);
  for (const auto& tf : tracked) ASSERT_EQ(tf.state, msg::TrackingState::kOk) << "frame " << tf.frame_index;
  const Pose3 err = s->route[149].inverse() * poses.back();
  // Looser than lock-step: how many keyframes mapping finishes in time depends on the machine's load (a
  // run beside other jobs ended 0.503 m off after 170 m).
  EXPECT_LT(err.translation().norm(), 0.8);
  EXPECT_LT(rotationDeg(err.linear()), 0.5);
}

// Tracking that waits for mapping (`pipeline.wait_for_mapping_ms`) sees the map lock-step would give it, so
// a threaded run repeats the lock-step run bit for bit while mapping keeps up (here the allowance is a minute
// and the frames come as fast as tracking takes them, so it always does).
TEST(SlamPipeline, ThreadedModeThatWaitsForMappingRepeatsLockStep) {
  const RenderedStretch* s = renderedStretch(300);
  if (!s) GTEST_SKIP() << "needs " << test::sharedData("kitti/poses/06.txt");
  const std::vector<StereoFrame> frames(s->frames.begin(), s->frames.begin() + 80);
  PipelineParams waiting(PipelineMode::kThreaded);
  waiting.wait_for_mapping_ms = 60000;
  std::vector<Pose3> lock_step, threaded;
  runOn(frames, s->cam, PipelineMode::kLockStep, &lock_step);
  const auto tracked = runOn(frames, s->cam, waiting, &threaded);
  ASSERT_EQ(lock_step.size(), threaded.size());
  for (size_t i = 0; i < tracked.size(); ++i) {
    EXPECT_EQ(tracked[i].mapping_queue, 0) << "frame " << i << " was tracked while mapping was busy";
    ASSERT_TRUE(lock_step[i].matrix() == threaded[i].matrix()) << "frame " << i << " differs";
  }
}

// The largest turn (degrees) between consecutive keyframes of a run, as tracked.
double largestTurnBetweenKeyframes(const std::vector<msg::TrackedFrame>& tracked) {
  double largest = 0;
  const msg::TrackedFrame* last = nullptr;
  for (const auto& tf : tracked) {
    if (tf.new_keyframe == kNoId) continue;
    if (last) largest = std::max(largest, rotationDeg((last->T_w_c.inverse() * tf.T_w_c).linear()));
    last = &tf;
  }
  return largest;
}

// `keyframe_max_turn_deg`: in route 06's first turn (frames 270-299, 40 degrees, up to 2.7 a frame) a
// keyframe comes at the first frame past the bound, so no two keyframes lie further apart than the bound and
// one frame's turn. Without the rule ORB-SLAM2's point counts let them lie 22 degrees apart there (measured
// 2026-11-29; with it 7.2).
TEST(SlamPipeline, AKeyframeComesWheneverTheCameraHasTurnedTheBound) {
  const RenderedStretch* s = renderedStretch(300);
  if (!s) GTEST_SKIP() << "needs " << test::sharedData("kitti/poses/06.txt");
  const std::vector<StereoFrame> frames(s->frames.begin() + 240, s->frames.end());
  TrackerParams turning;
  turning.keyframe_max_turn_deg = 5;
  const auto with_rule = runOn(frames, s->cam, PipelineMode::kLockStep, nullptr, turning);
  const auto without = runOn(frames, s->cam, PipelineMode::kLockStep);
  for (const auto& tf : with_rule) ASSERT_EQ(tf.state, msg::TrackingState::kOk) << "frame " << tf.frame_index;
  const double with_deg = largestTurnBetweenKeyframes(with_rule),
               without_deg = largestTurnBetweenKeyframes(without);
  std::cout << "largest turn between keyframes: " << with_deg << " deg with the rule, " << without_deg
            << " without\n";
  EXPECT_LT(with_deg, 5 + 3.0);
  EXPECT_GT(without_deg, 5 + 3.0) << "the stretch no longer tests the rule";
}

// Each bad frame is reported and skipped; the frames after it are tracked as if it had not come.
TEST(SlamPipeline, BadFramesAreReportedAndTrackingGoesOn) {
  const RenderedStretch* s = renderedStretch(300);
  if (!s) GTEST_SKIP() << "needs " << test::sharedData("kitti/poses/06.txt");
  SlamPipeline slam(s->cam, {}, {}, PipelineMode::kLockStep);
  for (int i = 0; i < 10; ++i) ASSERT_EQ(slam.process(s->frames[i]).state, msg::TrackingState::kOk);

  StereoFrame empty = s->frames[10];
  empty.left = cv::Mat();
  auto tf = slam.process(empty);
  EXPECT_NE(tf.problem.find("frame 10: empty left image"), std::string::npos) << tf.problem;

  StereoFrame mismatch = s->frames[10];
  cv::resize(mismatch.right, mismatch.right, cv::Size(mismatch.right.cols / 2, mismatch.right.rows / 2));
  tf = slam.process(mismatch);
  EXPECT_NE(tf.problem.find("left image is 1226x370 but right is 613x185"), std::string::npos) << tf.problem;

  StereoFrame colour = s->frames[10];
  cv::cvtColor(colour.left, colour.left, cv::COLOR_GRAY2BGR);
  cv::cvtColor(colour.right, colour.right, cv::COLOR_GRAY2BGR);
  tf = slam.process(colour);
  EXPECT_NE(tf.problem.find("images must be 8-bit grey (mono8)"), std::string::npos) << tf.problem;

  StereoFrame back = s->frames[10];
  back.stamp_s = 0.5;  // frame 9 was at 0.9 s
  tf = slam.process(back);
  EXPECT_NE(tf.problem.find("does not come after the last frame's"), std::string::npos) << tf.problem;

  // New pixels: a copied StereoFrame shares the cached frame's, and assigning Mat::zeros() would write into
  // them.
  StereoFrame black = s->frames[10];
  black.left = cv::Mat(black.left.size(), CV_8UC1, cv::Scalar(0));
  black.right = cv::Mat(black.right.size(), CV_8UC1, cv::Scalar(0));
  tf = slam.process(black);
  EXPECT_EQ(tf.state, msg::TrackingState::kLost);
  EXPECT_NE(tf.problem.find("lost"), std::string::npos) << tf.problem;

  // Frame 11 comes after a gap of two frames and a lost frame: tracking takes up the map again.
  for (int i = 11; i < 20; ++i) {
    tf = slam.process(s->frames[i]);
    EXPECT_NE(tf.state, msg::TrackingState::kLost) << "frame " << i << ": " << tf.problem;
  }
  const Pose3 err = s->route[19].inverse() * tf.T_w_c;
  EXPECT_LT(err.translation().norm(), 0.3);
}

// A bag played again: its first stamps come before the last frame's. Without a restarted clock every
// frame of the replay is refused; with it the replayed frames are found in the map (the recent keyframes
// see them) and tracked where they were.
TEST(SlamPipeline, AReplayIsTrackedAgainAfterTheClockRestarts) {
  const RenderedStretch* s = renderedStretch(300);
  if (!s) GTEST_SKIP() << "needs " << test::sharedData("kitti/poses/06.txt");
  SlamPipeline slam(s->cam, {}, {}, PipelineMode::kLockStep);
  for (int i = 0; i < 60; ++i) ASSERT_EQ(slam.process(s->frames[i]).state, msg::TrackingState::kOk) << i;
  msg::TrackedFrame tf = slam.process(s->frames[50]);
  EXPECT_NE(tf.problem.find("does not come after the last frame's"), std::string::npos) << tf.problem;
  slam.restartClock();
  int tracked = 0;
  for (int i = 50; i < 60; ++i) {
    StereoFrame f = s->frames[i];
    f.index = 60 + i;  // the runner's count goes on; the stamps are the first play's
    tf = slam.process(f);
    if (tf.state == msg::TrackingState::kLost) {
      EXPECT_LE(i, 51) << "still lost at replayed frame " << i << ": " << tf.problem;
      continue;
    }
    ++tracked;
    EXPECT_LT((s->route[i].translation() - tf.T_w_c.translation()).norm(), 0.3) << "replayed frame " << i;
  }
  EXPECT_GE(tracked, 8);
}

// Frames missing from the input: the motion model is carried over the time since the last tracked frame.
void expectTrackedAfterGap(const RenderedStretch& s, int gap) {
  SlamPipeline slam(s.cam, {}, {}, PipelineMode::kLockStep);
  for (int i = 0; i < 100; ++i) ASSERT_EQ(slam.process(s.frames[i]).state, msg::TrackingState::kOk) << i;
  for (int i = 100 + gap; i < 130 + gap; ++i) {
    const msg::TrackedFrame tf = slam.process(s.frames[i]);
    ASSERT_NE(tf.state, msg::TrackingState::kLost) << "frame " << i << ": " << tf.problem;
    EXPECT_LT((s.route[i].translation() - tf.T_w_c.translation()).norm(), 0.3) << "frame " << i;
  }
}

TEST(SlamPipeline, TrackingGoesOnAfterFiveMissingFrames) {
  const RenderedStretch* s = renderedStretch(300);
  if (!s) GTEST_SKIP() << "needs " << test::sharedData("kitti/poses/06.txt");
  expectTrackedAfterGap(*s, 5);
}

// The SLAM issue's case: 10 and 20 frames (12 m, 24 m) missing, on the road that does not repeat. The
// motion model is then 2-5 degrees off in rotation (the car leaves a bend at frame 100), and the map
// points now near were measured from 24 m further back; Tracker::recoverRotationFirst mends the rotation
// from far points and takes the pose from the frame's stereo against the keyframes' sightings. Errors are
// against the ground truth carried into the map's frame at the last frame before the gap (the map's own
// drift before it, 0.2-0.3 m, is not relocalisation's to mend). `first_m` bounds the first frame found
// again, `all_m` every frame of the 30 after the gap; at most the first two are lost.
void expectFoundAfterGap(const RenderedStretch& s, int start, int gap, double first_m, double all_m) {
  ASSERT_LE(start + gap + 30, s.first + static_cast<int>(s.frames.size()));
  SlamPipeline slam(s.cam, {}, {}, PipelineMode::kLockStep);
  Pose3 last;
  for (int i = s.first; i < start; ++i) {
    const msg::TrackedFrame tf = slam.process(s.frames[i - s.first]);
    ASSERT_EQ(tf.state, msg::TrackingState::kOk) << i;
    last = tf.T_w_c;
  }
  const Pose3 drift = last * s.route[start - 1].inverse();
  int lost = 0;
  bool found = false;
  for (int i = start + gap; i < start + gap + 30; ++i) {
    const msg::TrackedFrame tf = slam.process(s.frames[i - s.first]);
    if (tf.state == msg::TrackingState::kLost) {
      ++lost;
      EXPECT_LE(i, start + gap + 1) << "lost at frame " << i << ": " << tf.problem;
      continue;
    }
    const double off = ((drift * s.route[i]).translation() - tf.T_w_c.translation()).norm();
    EXPECT_LT(off, found ? all_m : first_m) << "frame " << i;
    found = true;
  }
  EXPECT_LE(lost, 1);
}

// Measured (bench_recovery --start 100 --lead 100 --gap 10): at most 0.28 m over the 30.
TEST(SlamPipeline, TrackingIsFoundAgainAfterTenMissingFrames) {
  const RenderedStretch* s = renderedStretch(340, true);
  if (!s) GTEST_SKIP() << "needs " << test::sharedData("kitti/poses/06.txt");
  expectFoundAfterGap(*s, 100, 10, 0.3, 0.3);
}

// 26 m skipped. Measured (--gap 20): frame 120 lost, 121 found 0.51 m off, then local BA places the next
// 1.1 m off, and the 27 after stay within 1.11 m (0.45 and 0.93 when the sightings were the last three in
// the replica's lists, which happened to be far ones: docs/decisions.md). How far the
// frames found again can be placed along the road rests on the depths of map points 40-150 m away, which
// every keyframe before the gap measured from as far (docs/results/2026-11-29-twenty-frame-recovery.md).
TEST(SlamPipeline, TrackingIsFoundAgainAfterTwentyMissingFrames) {
  const RenderedStretch* s = renderedStretch(340, true);
  if (!s) GTEST_SKIP() << "needs " << test::sharedData("kitti/poses/06.txt");
  expectFoundAfterGap(*s, 100, 20, 0.6, 1.2);
}

// The issue's bound, 0.3 m after 20 missing frames, where the car drives slowly: frames 350-449 mapped, then
// 470-499 (15 m skipped). The recovery holds it: the first frame is found 0.15 m off (bench_recovery --start
// 450 --lead 100 --gap 20). The first keyframe's local BA then moves it 0.38 m along the road, to the map's
// far points (0.51 m off, at most 0.60 over the 30; 0.28 before culling counted close stereo sightings
// twice, docs/decisions.md). At the usual 26-30 m skipped even the first frame does not hold it: the map's
// points then in view were measured from 40-70 m away and are metres off along the view
// (docs/results/2026-11-26-slam-measurements.md, "Why the found places are off").
TEST(SlamPipeline, TheFirstFrameAfterTwentyMissingOnASlowStretchIsFoundWithinThirtyCentimetres) {
  const RenderedStretch* s = renderedStretch(150, true, 350);
  if (!s) GTEST_SKIP() << "needs " << test::sharedData("kitti/poses/06.txt");
  expectFoundAfterGap(*s, 450, 20, 0.3, 0.8);
}

// After 20 missing frames on route 06 (frames 700-799 mapped, then 820-849) the map holds too little of the
// view to be found again: relocalisation's PnP kept 3-4 of 47 descriptor matches and tracking stayed lost
// for good. With `restart_after_lost` (3) tracking starts again at the motion model's prediction at the
// third lost frame, in a new map segment. Measured: 0.63 m off at the restart (the prediction's), at most
// 1.52 m over the 28 frames tracked (its 2 degrees of heading error, carried on).
TEST(SlamPipeline, TrackingStartsAgainAtThePredictionWhenTheMapHoldsTooLittleOfTheView) {
  const RenderedStretch* s = renderedStretch(150, true, 700);
  if (!s) GTEST_SKIP() << "needs " << test::sharedData("kitti/poses/06.txt");
  for (int restart : {0, 3}) {
    TrackerParams tp;
    tp.restart_after_lost = restart;
    SlamPipeline slam(s->cam, tp, {}, PipelineMode::kLockStep);
    Pose3 last;
    for (int i = 700; i < 800; ++i) {
      const msg::TrackedFrame tf = slam.process(s->frames[i - 700]);
      ASSERT_EQ(tf.state, msg::TrackingState::kOk) << i;
      last = tf.T_w_c;
    }
    const size_t keyframes_before = slam.mapper().keyframeCount();
    const Pose3 drift = last * s->route[799].inverse();
    int lost = 0, restarts = 0;
    for (int i = 820; i < 850; ++i) {
      const msg::TrackedFrame tf = slam.process(s->frames[i - 700]);
      if (tf.state == msg::TrackingState::kLost) {
        ++lost;
        continue;
      }
      restarts +=
          tf.problem.find("tracking started again at the motion model's prediction") != std::string::npos;
      const double off = ((drift * s->route[i]).translation() - tf.T_w_c.translation()).norm();
      EXPECT_LT(off, 2.0) << "restart_after_lost " << restart << ", frame " << i;
    }
    if (restart == 0) {
      EXPECT_EQ(lost, 30) << "found again without a restart: the test needs a place the map cannot find";
    } else {
      EXPECT_EQ(lost, restart - 1);
      EXPECT_EQ(restarts, 1);
      EXPECT_GT(slam.mapper().keyframeCount(), keyframes_before + 2) << "mapping took no keyframe after it";
    }
  }
}

// An operator's 2D Pose Estimate (Tracker::hintPose, the nodelet's /initialpose): the camera carried back
// 160 frames (about 190 m, 10 s later) to a place the map saw long ago. Without a vocabulary relocalisation
// tries only the most recent keyframes, and the frames stay lost; with a hint 1 m off the truth, the next
// frame is found near it.
TEST(SlamPipeline, APoseHintFindsAFrameCarriedFarFromTheRecentKeyframes) {
  const RenderedStretch* s = renderedStretch(340, true);
  if (!s) GTEST_SKIP() << "needs " << test::sharedData("kitti/poses/06.txt");
  SlamPipeline slam(s->cam, {}, {}, PipelineMode::kLockStep);
  Pose3 last;
  for (int i = 0; i < 200; ++i) {
    const msg::TrackedFrame tf = slam.process(s->frames[i]);
    ASSERT_NE(tf.state, msg::TrackingState::kLost) << i;
    last = tf.T_w_c;
  }
  const Pose3 drift = last * s->route[199].inverse();
  int next_index = 200;
  const double t0 = s->frames[199].stamp_s + 10;
  auto carried = [&](int i) {
    StereoFrame f = s->frames[i];
    f.index = next_index++;
    f.stamp_s = t0 + 0.1 * (i - 40);
    return f;
  };
  for (int i = 40; i < 43; ++i)
    EXPECT_EQ(slam.process(carried(i)).state, msg::TrackingState::kLost)
        << "frame " << i << " found without a hint";
  Pose3 hint = drift * s->route[43];
  hint.translation() += Eigen::Vector3d(0.8, 0, 0.6);  // 1 m off
  slam.hintPose(hint, 10);
  int found = 0;
  double worst = 0;
  for (int i = 43; i < 53; ++i) {
    const msg::TrackedFrame tf = slam.process(carried(i));
    if (tf.state == msg::TrackingState::kLost) continue;
    ++found;
    const double off = ((drift * s->route[i]).translation() - tf.T_w_c.translation()).norm();
    worst = std::max(worst, off);
    EXPECT_LT(off, 0.5) << "frame " << i;
  }
  std::cout << "with the hint: " << found << " of 10 frames found, at most " << worst << " m off\n";
  EXPECT_GE(found, 9);
}

// The covariance a tracked frame carries against its real error on a render: the error of the motion between
// consecutive frames (the map's own error, shared by both, mostly cancels there) against the two frames'
// predicted position variances, as the ratio of the summed squared errors to the summed predicted variances.
TEST(SlamPipeline, ATrackedFramesCovarianceMatchesItsFrameToFrameError) {
  const RenderedStretch* s = renderedStretch(300);
  if (!s) GTEST_SKIP() << "needs " << test::sharedData("kitti/poses/06.txt");
  const std::vector<msg::TrackedFrame> out = runOn(s->frames, s->cam, PipelineMode::kLockStep);
  const test::CovarianceCheck c = test::checkCovariances(out, s->route);
  std::cout << c.steps << " steps: rms frame-to-frame error " << c.rms_error_m << " m, predicted "
            << c.predicted_sd_m << " m, ratio of squares " << c.ratio << "\n";
  EXPECT_GE(c.steps, 290);
  // With pose_covariance_scale (15) the prediction is within a factor of 2.5 of the error, either way
  // (rendered 06: 1.37, real KITTI 06: 0.67).
  EXPECT_GT(c.ratio, 0.4);
  EXPECT_LT(c.ratio, 2.5);
}

// A tracking process restarted alone in the split graph: the new tracker takes local mapping's map (the
// whole_map update mapping sends a new subscriber), starts lost at its last keyframe, finds the frames after
// a second's gap in it, and issues keyframe and point ids the map has never held (mapping refuses ids it
// holds).
TEST(SlamPipeline, ARestartedTrackerTakesTheMapAndTracksOnInIt) {
  const RenderedStretch* s = renderedStretch(200, true);
  if (!s) GTEST_SKIP() << "needs " << test::sharedData("kitti/poses/06.txt");
  SlamPipeline slam(s->cam, {}, {}, PipelineMode::kLockStep);
  for (int i = 0; i < 150; ++i) ASSERT_NE(slam.process(s->frames[i]).state, msg::TrackingState::kLost) << i;
  const msg::LocalMapUpdatePtr whole = slam.mapper().wholeMap();
  ASSERT_TRUE(whole->whole_map);
  EXPECT_EQ(whole->keyframes.size(), slam.mapper().keyframeCount());
  EXPECT_GT(whole->tracking_keyframe_ids, 0u);

  Tracker young(s->cam);
  young.track(s->frames[150]);
  ASSERT_EQ(young.map().keyframeCount(), 1u);
  EXPECT_TRUE(young.givesWayTo(*whole)) << "a map of one keyframe begun before the graph's map came";

  Tracker restarted(s->cam);
  EXPECT_TRUE(restarted.givesWayTo(*whole));
  restarted.adoptMap(*whole);
  EXPECT_EQ(restarted.state(), msg::TrackingState::kLost);
  EXPECT_EQ(restarted.map().keyframeCount(), whole->keyframes.size());
  EXPECT_THROW(restarted.adoptMap(*whole), std::invalid_argument) << "only a tracker that has not started";
  std::set<uint64_t> held;
  for (const auto& k : whole->keyframes) held.insert(k.id);
  for (const auto& p : whole->points) held.insert(p.id);
  // The reference: where the graph that was not restarted puts the same frames in the same map (the map has
  // drifted 0.3-0.4 m from the truth by then; a new map would start at the origin, 150 m away).
  std::map<int, Pose3> uninterrupted;
  for (int i = 150; i < 200; ++i) uninterrupted[i] = slam.process(s->frames[i]).T_w_c;
  int found = 0, keyframes = 0;
  double worst = 0;
  for (int i = 160; i < 200; ++i) {  // ten frames missed while the process came back
    const Tracker::Output out = restarted.track(s->frames[i]);
    if (out.keyframe) {
      ++keyframes;
      EXPECT_EQ(held.count(out.keyframe->id), 0u) << "keyframe id issued again";
      EXPECT_GT(counterOf(out.keyframe->id), whole->tracking_keyframe_ids);
      for (const auto& p : out.keyframe->new_points)
        EXPECT_EQ(held.count(p.id), 0u) << "point id issued again";
    }
    if (out.frame.state == msg::TrackingState::kLost) continue;
    ++found;
    // A pose found from scratch carries the error far points give it (docs/decisions.md, recovery): 0.6 m
    // here.
    worst = std::max(worst, (uninterrupted[i].translation() - out.frame.T_w_c.translation()).norm());
  }
  std::cout << "after the restart: " << found << " of 40 frames tracked, " << keyframes
            << " keyframes made, at most " << worst
            << " m from where the graph that was not restarted put them\n";
  EXPECT_GE(found, 35);
  EXPECT_LT(worst, 1.0);
  EXPECT_GE(keyframes, 1);
  EXPECT_FALSE(restarted.givesWayTo(*whole)) << "a tracker on the map does not start over";
}

// The tracking stage as the nodelet runs it (tracking/tracking_stage.h): local mapping's map kept until the
// camera is known and then taken; keyframes counted in flight until mapping answers; a tracker on the map not
// restarted by it, a young one restarted for it; a reset without a fixed camera leaves no tracker.
TEST(TrackingStage, TakesLocalMappingsMapWhenTheCameraIsKnownAndCountsKeyframesInFlight) {
  const RenderedStretch* s = renderedStretch(200, true);
  if (!s) GTEST_SKIP() << "needs " << test::sharedData("kitti/poses/06.txt");
  SlamPipeline slam(s->cam, {}, {}, PipelineMode::kLockStep);
  for (int i = 0; i < 150; ++i) slam.process(s->frames[i]);
  const msg::LocalMapUpdatePtr whole = slam.mapper().wholeMap();

  TrackingStage stage({}, std::nullopt, 5);
  EXPECT_EQ(stage.tracker(), nullptr);
  EXPECT_EQ(stage.adopt(whole), TrackingStage::Adopted::kKept);
  EXPECT_EQ(stage.mapsAdopted(), 0u);
  stage.setCamera(s->cam);
  ASSERT_NE(stage.tracker(), nullptr);
  EXPECT_EQ(stage.mapsAdopted(), 1u);
  EXPECT_EQ(stage.tracker()->map().keyframeCount(), whole->keyframes.size());
  EXPECT_EQ(stage.tracker()->state(), msg::TrackingState::kLost);

  int keyframes = 0;
  for (int i = 155; i < 200 && keyframes == 0; ++i)
    keyframes += stage.track(s->frames[i], i).keyframe != nullptr;
  ASSERT_EQ(keyframes, 1) << "no keyframe made in the map taken";
  EXPECT_EQ(stage.inFlight().count(), 1);
  stage.apply(msg::LocalMapUpdate{}, 200);  // mapping's answer
  EXPECT_EQ(stage.inFlight().count(), 0);
  const Tracker* running = stage.tracker();
  EXPECT_EQ(stage.adopt(whole), TrackingStage::Adopted::kBehind)
      << "a tracker on the map does not start over; the map lacks the keyframe it made";
  EXPECT_EQ(stage.tracker(), running);
  EXPECT_EQ(stage.takeResend(200).size(), 1u);
  stage.reset();
  EXPECT_EQ(stage.tracker(), nullptr);

  TrackingStage fixed({}, s->cam, 5);  // a camera from parameters: a tracker at once, and after a reset
  ASSERT_NE(fixed.tracker(), nullptr);
  fixed.track(s->frames[150], 0);
  ASSERT_EQ(fixed.tracker()->map().keyframeCount(), 1u);
  EXPECT_EQ(fixed.adopt(whole), TrackingStage::Adopted::kTakenAfterStartOver) << "a young map gives way";
  EXPECT_EQ(fixed.tracker()->map().keyframeCount(), whole->keyframes.size());
  fixed.reset();
  EXPECT_NE(fixed.tracker(), nullptr);
}

// Local mapping's process restarted from its autosave (the split launch with respawn): the map it holds
// lacks the keyframes tracking sent after that save. The running tracker does not take that map, but sends
// those keyframes again; the restarted mapper then holds every keyframe tracking made, issues point ids
// that collide with none its predecessor issued, and tracking goes on in it.
TEST(TrackingStage, ALocalMappingRestartedFromAnAutosaveGetsTheKeyframesItLacksAgain) {
  const RenderedStretch* s = renderedStretch(200, true);
  if (!s) GTEST_SKIP() << "needs " << test::sharedData("kitti/poses/06.txt");
  test::TempDir dir;
  const std::string autosave = dir.path() + "/local_mapping.autosave";
  LocalMapper live{LocalMapperParams{}};
  TrackingStage stage({}, s->cam, 5, 100);
  auto drive = [&](LocalMapper& mapper, int from, int to) {
    for (int i = from; i < to; ++i) {
      const Tracker::Output out = stage.track(s->frames[i], i);
      ASSERT_EQ(out.frame.state, msg::TrackingState::kOk) << "frame " << i;
      if (out.keyframe) stage.apply(*mapper.process(*out.keyframe).update, i);
    }
  };
  drive(live, 0, 60);
  saveStateFile(live, autosave, "local_mapping", 7);
  drive(live, 60, 120);
  const uint64_t made = live.wholeMap()->tracking_keyframe_ids;

  LocalMapper restarted{LocalMapperParams{}};
  loadStateFile(restarted, autosave, "local_mapping");
  restarted.resumeAfterRestart();
  const msg::LocalMapUpdatePtr behind = restarted.wholeMap();
  ASSERT_LT(behind->tracking_keyframe_ids, made) << "the autosave should lack the last keyframes";
  ASSERT_EQ(stage.adopt(behind), TrackingStage::Adopted::kBehind);
  uint64_t missing = 99;
  const std::vector<msg::KeyFramePtr> again = stage.takeResend(120, &missing);
  EXPECT_EQ(missing, 0u);
  EXPECT_EQ(again.size(), made - behind->tracking_keyframe_ids);
  EXPECT_EQ(stage.inFlight().count(), 0) << "keyframes sent again must not stop new ones";
  std::set<MapPointId> before, saved;  // the point ids of the first mapper's map, and of its autosave
  for (const msg::MapPoint& p : live.wholeMap()->points) before.insert(p.id);
  for (const msg::MapPoint& p : behind->points) saved.insert(p.id);
  for (const msg::KeyFramePtr& k : again) stage.apply(*restarted.process(*k).update, 120);
  EXPECT_EQ(restarted.wholeMap()->tracking_keyframe_ids, made);
  EXPECT_EQ(stage.adopt(restarted.wholeMap()), TrackingStage::Adopted::kIgnored) << "nothing lacking now";

  drive(restarted, 120, 200);
  int made_after = 0;
  for (const msg::MapPoint& p : restarted.wholeMap()->points) {
    if (issuerOf(p.id) != IdIssuer::kLocalMapping || saved.count(p.id)) continue;
    ++made_after;
    EXPECT_EQ(before.count(p.id), 0u) << "point id " << p.id << " issued twice";
  }
  EXPECT_GT(made_after, 0) << "the restarted mapper triangulated no point";
  EXPECT_GT(restarted.keyframeCount(), live.keyframeCount()) << "no keyframe made after the restart";
}

// A tracking reset (or a loaded map) while local mapping keeps its map: the new tracker's ids start a new
// session, so mapping takes its keyframes. Before sessions, the fresh tracker issued keyframe 1 again and
// mapping refused every keyframe it made as "already in the map".
TEST(TrackingStage, ATrackerAfterAResetIssuesNoIdLocalMappingAlreadyHolds) {
  const RenderedStretch* s = renderedStretch(120, true);
  if (!s) GTEST_SKIP() << "needs " << test::sharedData("kitti/poses/06.txt");
  LocalMapper mapper{LocalMapperParams{}};
  TrackingStage stage({}, s->cam, 5);
  std::set<SlamKeyframeId> ids;
  auto drive = [&](int from, int to) {
    for (int i = from; i < to; ++i) {
      const Tracker::Output out = stage.track(s->frames[i], i);
      if (!out.keyframe) continue;
      EXPECT_TRUE(ids.insert(out.keyframe->id).second)
          << "keyframe id " << out.keyframe->id << " issued twice";
      // Mapping refuses a keyframe or a new point whose id it holds (LocalMapper::insert).
      EXPECT_NO_THROW(stage.apply(*mapper.process(*out.keyframe).update, i)) << "frame " << i;
    }
  };
  drive(0, 50);
  const size_t before = mapper.keyframeCount();
  ASSERT_GT(before, 3u);
  const uint64_t issued = stage.tracker()->keyframeIdsIssued();
  stage.reset();
  EXPECT_GE(stage.tracker()->keyframeIdsIssued(), uint64_t{1} << 32)
      << "the fresh tracker is in a new session";
  drive(50, 120);
  EXPECT_GT(mapper.keyframeCount(), before) << "mapping took no keyframe of the tracker after the reset";
  EXPECT_GT(stage.tracker()->keyframeIdsIssued(), issued);

  // A map loaded into the stage continues after the highest ids too (its file's own may be older).
  auto loaded = stage.freshTracker(s->cam);
  stage.startOver(std::move(loaded));
  EXPECT_GE(stage.tracker()->keyframeIdsIssued(), uint64_t{2} << 32);
}

// Frame 309 of route 06 comes out of a bend: after 10 missing frames the ordinary tracking (the motion
// model, then matching without a prediction) put the frame 8 m behind the truth and 7 degrees off, with
// enough inliers to call it tracked. A pose the camera could not have reached since the last tracked
// frame is refused on every path, not only in recovery; here relocalisation then finds it.
TEST(SlamPipeline, FramesAfterAGapAreNotTrackedWhereTheCameraCouldNotBe) {
  const RenderedStretch* s = renderedStretch(340, true);
  if (!s) GTEST_SKIP() << "needs " << test::sharedData("kitti/poses/06.txt");
  expectFoundAfterGap(*s, 300, 10, 0.3, 0.3);
}

// The road of these renders repeats every 8 m (WorldParams::aperiodic_ground), and after 10 missing frames
// relocalisation from scratch found 58-68 inliers at poses 24-39 m behind the truth. While the motion model
// still predicts, a pose the camera could not have reached is refused: the frame stays lost instead. The
// rotation-first recovery finds these frames near the prediction before relocalisation runs, so it is
// switched off here to reach the gate.
TEST(SlamPipeline, ARecoveredPoseTheCameraCouldNotHaveReachedIsRefused) {
  const RenderedStretch* s = renderedStretch(300);
  if (!s) GTEST_SKIP() << "needs " << test::sharedData("kitti/poses/06.txt");
  TrackerParams tp;
  tp.recover_rotation_first = false;
  tp.restart_after_lost = 0;  // else tracking starts afresh at the prediction after three lost frames
  SlamPipeline slam(s->cam, tp, {}, PipelineMode::kLockStep);
  for (int i = 0; i < 100; ++i) ASSERT_EQ(slam.process(s->frames[i]).state, msg::TrackingState::kOk) << i;
  int refused = 0;
  for (int i = 110; i < 129; ++i) {  // the prediction holds for 3 s after frame 99
    const msg::TrackedFrame tf = slam.process(s->frames[i]);
    refused += tf.problem.find("from the motion model's prediction after") != std::string::npos;
    if (tf.state != msg::TrackingState::kLost) {
      EXPECT_LT((s->route[i].translation() - tf.T_w_c.translation()).norm(), 1.0) << "frame " << i;
    }
  }
  EXPECT_GE(refused, 1);
}

// The camera is carried back 90 frames (about 110 m) to a place the map holds, which takes it 5 s: the
// motion model no longer predicts, the recent keyframes are elsewhere, and only the vocabulary over every
// keyframe finds it. The road does not repeat here: on the 8 m road the first frame back matched the last
// frame's road, pixel for pixel, and was "tracked" 109 m from the truth.
// The vocabulary is small (small_vocabulary.h) and trained on frames 150-299, which the map never sees, so
// that a clean clone tests relocalisation too.
TEST(SlamPipeline, KidnappedCameraIsFoundByTheVocabulary) {
  const RenderedStretch* s = renderedStretch(340, true);
  if (!s) GTEST_SKIP() << "needs " << test::sharedData("kitti/poses/06.txt");
  test::TempDir dir;
  const std::string voc = dir / "hbow.bin";
  test::trainSmallHbow(s->frames, 150, 300, 5, voc);
  TrackerParams tp;
  tp.vocabulary = HbowRecognizer::loadVocabulary(voc);
  SlamPipeline slam(s->cam, tp, {}, PipelineMode::kLockStep);
  for (int i = 0; i < 150; ++i) ASSERT_EQ(slam.process(s->frames[i]).state, msg::TrackingState::kOk) << i;
  int found = -1;
  for (int k = 0; k < 30; ++k) {
    StereoFrame f = s->frames[60 + k];
    f.index = 150 + k;
    f.stamp_s = 20.0 + 0.1 * k;  // time goes on; the place goes back
    const msg::TrackedFrame tf = slam.process(f);
    if (tf.state == msg::TrackingState::kLost) {
      EXPECT_LT(found, 0) << "lost again at frame " << 60 + k << " after it was found";
      continue;
    }
    if (found < 0) found = 60 + k;
    EXPECT_LT((s->route[60 + k].translation() - tf.T_w_c.translation()).norm(), 0.3) << "frame " << 60 + k;
  }
  ASSERT_GE(found, 0) << "never relocalised";
  EXPECT_LE(found, 62) << "found only at frame " << found;
}

TEST(SlamPipeline, CameraWithoutFocalLengthIsRefused) {
  StereoCamera cam = kitti00Camera();
  cam.fx = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW_WITH(Tracker t(cam), std::invalid_argument, "fx, fy and baseline must be positive");
  cam = kitti00Camera();
  cam.fx = 0;
  EXPECT_THROW_WITH(Tracker t(cam), std::invalid_argument, "fx, fy and baseline must be positive");
}
