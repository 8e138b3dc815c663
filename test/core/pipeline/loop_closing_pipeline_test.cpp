// Loop closing end to end: a rendered drive of 1.25 laps round a 50 x 80 m block (the built-in route; no
// data files needed), tracked, mapped, searched for loops and corrected in one pipeline. The hbow vocabulary
// is trained here, small (1000 words), on every 10th frame of the first lap: the point is the closing, not
// the vocabulary.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <functional>

#include "binloop/features/orb_slam_extractor.h"
#include "binloop/pipeline/slam_pipeline.h"
#include "binloop/place/model_training.h"
#include "binloop/sim/builtin_route.h"
#include "binloop/sim/stereo_renderer.h"
#include "binloop/sim/texture_bank.h"
#include "core/pipeline/loop_drive.h"
#include "support/test_support.h"

using namespace binloop;
using binloop::test::LoopDrive;
using binloop::test::loopDrive;

namespace {

struct DriveRun {
  std::vector<Pose3> poses;  // every frame, on its reference keyframe's final pose
  std::vector<SlamPipeline::LoopLogEntry> log;
  size_t unresolved = 0;  // frames whose reference keyframe mapping does not know
};

using BeforeFinish = std::function<void(SlamPipeline&, const std::vector<msg::TrackedFrame>&)>;

DriveRun runDrive(const LoopDrive& d, bool close_loops, PipelineMode mode = PipelineMode::kLockStep,
                  const BeforeFinish& before_finish = {}, const LocalMapperParams& mp = {},
                  LocalMapper::GlobalBaStats* global_ba = nullptr) {
  std::optional<LoopClosingSetup> loops;
  if (close_loops) {
    loops = test::tinyHbowLoopSetup(d);
  }
  SlamPipeline slam(d.cam, {}, mp, mode, loops);
  std::vector<msg::TrackedFrame> tracked;
  for (const auto& f : d.frames) tracked.push_back(slam.process(f));
  if (before_finish) before_finish(slam, tracked);
  slam.finish();
  DriveRun r;
  for (const auto& tf : tracked) {
    Pose3 T_ref;
    const bool known = tf.reference != kNoId && slam.mapper().keyframePose(tf.reference, &T_ref);
    r.poses.push_back(known ? Pose3(T_ref * tf.T_ref_c) : tf.T_w_c);
    r.unresolved += !known;
  }
  r.log = slam.loopLog();
  if (global_ba) *global_ba = slam.mapper().globalBaStats();
  return r;
}

std::vector<const msg::LoopClosure*> accepted(const DriveRun& r) {
  std::vector<const msg::LoopClosure*> out;
  for (const auto& e : r.log)
    for (const auto& c : e.closures)
      if (c->status == msg::LoopStatus::kAccepted) out.push_back(c.get());
  return out;
}

}  // namespace

// Also lock-step determinism with loop closing on: a second run gives the same poses bit for bit.
TEST(LoopClosingPipeline, TheRevisitIsClosedCorrectlyTheErrorThereDropsAndRerunsAreIdentical) {
  const LoopDrive* d = loopDrive();
  if (!d) GTEST_SKIP() << "needs the texture photos of ../shared/data";
  const DriveRun open = runDrive(*d, false);
  const DriveRun closed = runDrive(*d, true);
  const auto loops = accepted(closed);
  ASSERT_FALSE(loops.empty()) << "no loop accepted";
  for (const msg::LoopClosure* c : loops) {
    const double apart =
        (d->route[c->query_frame].translation() - d->route[c->match_frame].translation()).norm();
    EXPECT_LT(apart, 10) << "frames " << c->query_frame << " and " << c->match_frame << ": " << c->detail;
    EXPECT_GT(c->query_frame, d->lap - 20);
  }
  // The error at the end of the drive (back over the start), with and without loop closing.
  const size_t last = d->frames.size() - 1;
  const double err_open = (open.poses[last].translation() - d->route[last].translation()).norm();
  const double err_closed = (closed.poses[last].translation() - d->route[last].translation()).norm();
  std::cout << "end error: " << err_open << " m open, " << err_closed << " m closed (" << loops.size()
            << " loops)\n";
  EXPECT_LT(err_closed, 0.25);
  EXPECT_LT(err_closed, 0.5 * err_open);

  const DriveRun again = runDrive(*d, true);
  ASSERT_EQ(again.poses.size(), closed.poses.size());
  for (size_t i = 0; i < again.poses.size(); ++i)
    ASSERT_TRUE(again.poses[i].matrix() == closed.poses[i].matrix()) << "frame " << i;
  EXPECT_EQ(accepted(again).size(), loops.size());
}

// Threaded, as the nodelets run: the loop stages on their own thread, the correction reaching mapping and
// tracking while frames keep coming. At the end two external loops are added: the start against the second
// pass over it (verified and accepted) and the second pass against the far side of the block (rejected).
TEST(LoopClosingPipeline, ThreadedModeClosesTheLoopAndVerifiesExternalLoops) {
  const LoopDrive* d = loopDrive();
  if (!d) GTEST_SKIP() << "needs the texture photos of ../shared/data";
  auto isKeyframe = [](const SlamPipeline& slam, const msg::TrackedFrame& tf) {
    return tf.new_keyframe != kNoId && slam.tracker().map().keyframe(tf.new_keyframe) != nullptr;
  };
  auto keyframeAfter = [&](const SlamPipeline& slam, const std::vector<msg::TrackedFrame>& tracked,
                           size_t frame) {
    for (size_t i = frame; i < tracked.size(); ++i)
      if (isKeyframe(slam, tracked[i])) return i;
    return tracked.size();
  };
  // The second pass's keyframe nearest the start in the ground truth: which frames become keyframes depends
  // on the threads' timing, and a pair 10 m apart sees too little in common to be a fair test of the API.
  auto nearestKeyframeAfter = [&](const SlamPipeline& slam, const std::vector<msg::TrackedFrame>& tracked,
                                  size_t from, size_t to) {
    size_t best = tracked.size();
    double best_d = 1e9;
    for (size_t i = from; i < tracked.size(); ++i) {
      const double dist = (d->route[i].translation() - d->route[to].translation()).norm();
      if (isKeyframe(slam, tracked[i]) && dist < best_d) best = i, best_d = dist;
    }
    return best;
  };
  const DriveRun r =
      runDrive(*d, true, PipelineMode::kThreaded, [&](SlamPipeline& slam, const auto& tracked) {
        const size_t start_frame = keyframeAfter(slam, tracked, 5),
                     far_frame = keyframeAfter(slam, tracked, d->lap / 2);
        ASSERT_LT(start_frame, tracked.size());
        ASSERT_LT(far_frame, tracked.size());
        const size_t again_frame = nearestKeyframeAfter(slam, tracked, d->lap, start_frame);
        ASSERT_LT(again_frame, tracked.size());
        const SlamKeyframeId start = tracked[start_frame].new_keyframe, far = tracked[far_frame].new_keyframe,
                             again = tracked[again_frame].new_keyframe;
        slam.addExternalLoop(again, start, "operator");
        slam.addExternalLoop(again, far, "operator");
      });
  std::vector<std::string> external;
  for (const auto& e : r.log)
    for (const auto& c : e.closures) {
      std::cout << c->model << " " << c->query_frame << "->" << c->match_frame << " " << c->status << ": "
                << c->detail << "\n";
      if (c->model == "operator")
        external.push_back(msg::loopStatusName(c->status) + std::string(": ") + c->detail);
    }
  ASSERT_EQ(external.size(), 2u);
  EXPECT_EQ(external[0].rfind("accepted", 0), 0u) << external[0];
  // The far side shares textures with the start (the world repeats its photos), so a few matches are found.
  EXPECT_TRUE(external[1].rfind("too_few_matches", 0) == 0 || external[1].rfind("no_consensus", 0) == 0)
      << external[1];
  const auto loops = accepted(r);
  size_t detected = 0;
  for (const msg::LoopClosure* c : loops) {
    EXPECT_LT((d->route[c->query_frame].translation() - d->route[c->match_frame].translation()).norm(), 10);
    detected += c->model != "operator";
  }
  ASSERT_GT(detected, 0u) << "the detector closed no loop";
  const size_t last = d->frames.size() - 1;
  const double err = (r.poses[last].translation() - d->route[last].translation()).norm();
  std::cout << "end error: " << err << " m (" << loops.size() << " loops accepted";
  for (const msg::LoopClosure* c : loops) std::cout << ", " << c->query_frame << "->" << c->match_frame;
  std::cout << ")\n";
  EXPECT_LT(err, 0.3);
}

// Threaded with a global BA after each loop: it runs beside mapping on a copy of the map and is merged when
// done, keyframes added meanwhile moved with their spanning-tree ancestor; the map keeps every keyframe and
// the end of the drive stays where the loop put it.
TEST(LoopClosingPipeline, ABackgroundGlobalBaIsMergedWithoutLosingKeyframesAddedMeanwhile) {
  const LoopDrive* d = loopDrive();
  if (!d) GTEST_SKIP() << "needs the texture photos of ../shared/data";
  LocalMapperParams mp;
  mp.global_ba_after_loop = true;
  LocalMapper::GlobalBaStats g;
  const DriveRun r = runDrive(*d, true, PipelineMode::kThreaded, {}, mp, &g);
  std::cout << "global BA: " << g.started << " started, " << g.merged << " merged, " << g.aborted
            << " stopped by a loop; the last over " << g.last_keyframes << " keyframes in " << g.last.ms()
            << " ms, " << g.last_added_meanwhile << " keyframes added meanwhile, " << g.last.iterations
            << " iterations (" << g.last.robust_iterations << " with Huber), cost " << g.last.initial_cost
            << " -> " << g.last.final_cost << ", " << g.last.num_outliers << " observations removed\n";
  size_t detected = 0;
  for (const auto* c : accepted(r)) detected += c->model != "operator";
  ASSERT_GT(detected, 0u) << "the detector closed no loop";
  EXPECT_GE(g.started, 1);
  EXPECT_EQ(g.merged + g.aborted, g.started);
  EXPECT_GE(g.merged, 1);
  EXPECT_GT(g.last_keyframes, 30);
  // Its report is the merged solve's: within the iteration caps, and the map fits its inliers better.
  EXPECT_GT(g.last.iterations, 0);
  EXPECT_LE(g.last.robust_iterations, mp.global_ba_robust_iterations);
  EXPECT_LE(g.last.iterations, mp.global_ba_robust_iterations + mp.global_ba_refine_iterations);
  EXPECT_LT(g.last.final_cost, g.last.initial_cost);
  // Every frame's reference keyframe is still in the map (or was culled and follows its parent).
  EXPECT_EQ(r.unresolved, 0u);
  const size_t last = d->frames.size() - 1;
  const double err = (r.poses[last].translation() - d->route[last].translation()).norm();
  std::cout << "end error: " << err << " m\n";
  EXPECT_LT(err, 0.3);
}

// A model that cannot be made is refused when it is asked for, not on the loop stage's thread mid-run.
TEST(LoopClosingPipeline, ASwitchToAModelThatCannotBeMadeIsRefusedAtOnce) {
  const std::string dir = std::string(BINLOOP_ROOT_DIR) + "/vocab/kitti08";
  if (!test::exists(dir + "/vlad.bin")) GTEST_SKIP() << "needs " << dir << "/vlad.bin";
  test::TempDir empty;
  LoopClosingSetup l;
  l.detector.model = "vlad";
  l.make_model = [&](const std::string& name) {
    RecognizerOptions ro;
    ro.model_file = (name == "vladpq" ? empty.path() : dir) + "/" + name + ".bin";
    return makePlaceRecognizer(name, ro);
  };
  const StereoCamera cam = kittiCameraByName("kitti04");
  LoopClosingSetup bad = l;
  bad.switches = {{5, "vladpq"}};
  EXPECT_THROW(SlamPipeline(cam, {}, {}, PipelineMode::kThreaded, bad), PlaceError);
  SlamPipeline slam(cam, {}, {}, PipelineMode::kThreaded, l);
  EXPECT_THROW(slam.switchDetector("vladpq"), PlaceError);
  EXPECT_NO_THROW(slam.switchDetector("hmvlad"));
  SlamPipeline off(cam, {}, {}, PipelineMode::kLockStep);
  EXPECT_THROW(off.switchDetector("vlad"), PlaceError);
  EXPECT_THROW(off.addExternalLoop(1, 2), PlaceError);
}
