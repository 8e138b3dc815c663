// Saving and loading the map (every stage's state file, SlamPipeline::saveMap/loadMap, the same files as the
// ROS map services): a round trip changes no byte, a loaded map is tracked, extended and closed as if the
// drive had never stopped, and broken or mismatched files are refused with a reason.
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <iterator>

#include "binloop/io/state_file.h"
#include "binloop/pipeline/slam_pipeline.h"
#include "binloop/place/hbow_recognizer.h"
#include "core/pipeline/loop_drive.h"
#include "support/test_support.h"

using namespace binloop;
using binloop::test::LoopDrive;
using binloop::test::loopDrive;

namespace {

const char* const kStages[] = {"tracking", "local_mapping", "loop_detector", "loop_closing"};

LoopClosingSetup loopSetup(const LoopDrive& d, const std::string& identity = "tiny hbow") {
  LoopClosingSetup l = test::tinyHbowLoopSetup(d);
  l.model_identity = [identity](const std::string&) { return identity; };
  return l;
}

TrackerParams trackerParams(const LoopDrive& d) {
  TrackerParams tp;
  tp.vocabulary = HbowRecognizer::loadVocabulary(d.vocabulary);
  tp.vocabulary_identity = "tiny hbow";
  return tp;
}

std::string bytesOf(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// The first lap, mapped with loop closing on, saved into `dir`.
void saveFirstLap(const LoopDrive& d, const std::string& dir) {
  SlamPipeline slam(d.cam, trackerParams(d), {}, PipelineMode::kLockStep, loopSetup(d));
  for (size_t i = 0; i < d.lap; ++i) slam.process(d.frames[i]);
  slam.finish();
  slam.saveMap(dir);
}

}  // namespace

TEST(MapSaveLoad, ARoundTripChangesNoByteAndTheLoadedMapIsTrackedAndClosed) {
  const LoopDrive* d = loopDrive();
  if (!d) GTEST_SKIP() << "needs the texture photos of ../shared/data";
  test::TempDir dir;
  const std::string first = dir / "first", again = dir / "again";
  saveFirstLap(*d, first);

  SlamPipeline loaded(d->cam, trackerParams(*d), {}, PipelineMode::kLockStep, loopSetup(*d));
  loaded.loadMap(first);
  loaded.saveMap(again);
  for (const char* s : kStages) {
    std::string a = bytesOf(stageStatePath(first, s)), b = bytesOf(stageStatePath(again, s));
    EXPECT_GT(a.size(), 1000u) << s;
    // Every byte but the map id after the stage's name, which names the save (a new one for every save).
    const size_t id_at = 32 + std::strlen(s);
    EXPECT_NE(a.substr(id_at, 8), b.substr(id_at, 8)) << s << ": two saves with one map id";
    a.replace(id_at, 8, 8, '\0');
    b.replace(id_at, 8, 8, '\0');
    EXPECT_TRUE(a == b) << s << ": a load and a save changed the state file";
  }
  const size_t keyframes = loaded.mapper().keyframeCount();
  EXPECT_GT(keyframes, 20u);
  EXPECT_EQ(loaded.tracker().map().keyframeCount(), keyframes);
  EXPECT_EQ(loaded.tracker().state(), msg::TrackingState::kLost);

  // The rest of the drive, over the start again: tracked in the loaded map (its frame is the first lap's),
  // new keyframes with new ids, and the revisit closed against keyframes of the first lap.
  SlamKeyframeId max_loaded = 0;
  for (const auto& k : loaded.mapper().keyframes()) max_loaded = std::max(max_loaded, k.id);
  size_t lost = 0;
  msg::TrackedFrame last;
  for (size_t i = d->lap; i < d->frames.size(); ++i) {
    last = loaded.process(d->frames[i]);
    if (last.state == msg::TrackingState::kLost) ++lost;
    if (last.new_keyframe != kNoId) {
      EXPECT_GT(last.new_keyframe, max_loaded) << "an id issued twice";
    }
  }
  loaded.finish();
  EXPECT_LE(lost, 2u) << "frames lost after the load";
  EXPECT_GT(loaded.mapper().keyframeCount(), keyframes);
  Pose3 T_ref;
  ASSERT_TRUE(loaded.mapper().keyframePose(last.reference, &T_ref));
  const double err = ((T_ref * last.T_ref_c).translation() - d->route.back().translation()).norm();
  size_t accepted = 0;
  for (const auto& e : loaded.loopLog())
    for (const auto& c : e.closures)
      if (c->status == msg::LoopStatus::kAccepted) {
        ++accepted;
        EXPECT_LT(c->match_frame, d->lap) << "the loop should reach back into the loaded map";
      }
  std::cout << "after the load: " << lost << " frames lost, end error " << err << " m, " << accepted
            << " loops accepted\n";
  EXPECT_GE(accepted, 1u);
  EXPECT_LT(err, 0.5);
}

// Localisation only on a loaded map: the second pass over the start is found in the first lap's map, every
// pose where the route is, and the map is left as loaded (no keyframe made, so mapping gets nothing).
TEST(MapSaveLoad, LocalisationOnlyTracksInTheLoadedMapAndChangesNothing) {
  const LoopDrive* d = loopDrive();
  if (!d) GTEST_SKIP() << "needs the texture photos of ../shared/data";
  test::TempDir dir;
  saveFirstLap(*d, dir / "map");

  TrackerParams tp = trackerParams(*d);
  tp.localize_only = true;
  SlamPipeline loaded(d->cam, tp, {}, PipelineMode::kLockStep, loopSetup(*d));
  loaded.loadMap(dir / "map");
  const size_t keyframes = loaded.mapper().keyframeCount();
  size_t tracked = 0, made = 0;
  double worst = 0;
  for (size_t i = d->lap; i < d->frames.size(); ++i) {
    const msg::TrackedFrame f = loaded.process(d->frames[i]);
    made += f.new_keyframe != kNoId;
    if (f.state == msg::TrackingState::kLost || f.state == msg::TrackingState::kNotInitialized) continue;
    ++tracked;
    worst = std::max(worst, (f.T_w_c.translation() - d->route[i].translation()).norm());
    EXPECT_GT(f.pose_covariance.trace(), 0) << "frame " << i << ": a tracked frame carries its covariance";
  }
  loaded.finish();
  const size_t frames = d->frames.size() - d->lap;
  std::cout << "localisation only: " << tracked << " of " << frames << " frames tracked, at most " << worst
            << " m from the route\n";
  EXPECT_EQ(made, 0u);
  EXPECT_EQ(loaded.mapper().keyframeCount(), keyframes);
  EXPECT_EQ(loaded.tracker().map().keyframeCount(), keyframes);
  EXPECT_GE(tracked, frames * 9 / 10);
  EXPECT_LT(worst, 0.5);

  SlamPipeline no_map(d->cam, tp, {}, PipelineMode::kLockStep);
  const msg::TrackedFrame f = no_map.process(d->frames[0]);
  EXPECT_EQ(f.state, msg::TrackingState::kNotInitialized);
  EXPECT_NE(f.problem.find("no map to localise in"), std::string::npos) << f.problem;
}

TEST(MapSaveLoad, BrokenOrMismatchedFilesAreRefusedWithTheReason) {
  const LoopDrive* d = loopDrive();
  if (!d) GTEST_SKIP() << "needs the texture photos of ../shared/data";
  test::TempDir dir;
  const std::string map = dir / "map";
  saveFirstLap(*d, map);
  auto loadInto = [&](const std::string& from, const std::string& identity = "tiny hbow") {
    SlamPipeline slam(d->cam, trackerParams(*d), {}, PipelineMode::kLockStep, loopSetup(*d, identity));
    slam.loadMap(from);
  };
  EXPECT_THROW_WITH(loadInto(dir / "nothing"), DataError, "no such folder");
  // another vocabulary for the loop model than the one the map's index was built with
  EXPECT_THROW_WITH(loadInto(map, "another hbow"), DataError, "index was built with tiny hbow");

  const std::string path = stageStatePath(map, "local_mapping");
  const std::string good = bytesOf(path);
  auto rewrite = [&](const std::string& bytes) {
    std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
  };
  rewrite(good.substr(0, good.size() / 2));
  EXPECT_THROW_WITH(loadInto(map), DataError, "truncated state file");
  std::string flipped = good;
  flipped[flipped.size() - 100] ^= 0x10;
  rewrite(flipped);
  EXPECT_THROW_WITH(loadInto(map), DataError, "checksum differs");
  rewrite(bytesOf(stageStatePath(map, "tracking")));
  EXPECT_THROW_WITH(loadInto(map), DataError,
                    "this is the tracking stage's state, not the local_mapping stage's");
  rewrite("not a state file at all, just some text that is long enough");
  EXPECT_THROW_WITH(loadInto(map), DataError, "not a binloop state file");
  rewrite(good);
  EXPECT_NO_THROW(loadInto(map));

  // A folder mixing two saves of the same map is refused before any stage reads a byte.
  const std::string later = dir / "later";
  saveFirstLap(*d, later);
  rewrite(bytesOf(stageStatePath(later, "local_mapping")));
  EXPECT_THROW_WITH(loadInto(map), DataError, "the folder mixes two saves");
  rewrite(good);
  EXPECT_NO_THROW(loadInto(map));

  // A tracker with another camera, or other extractor settings, cannot use the map's points.
  StereoCamera other = d->cam;
  other.fx += 10;
  Tracker t(other, trackerParams(*d));
  StateReader r(stageStatePath(map, "tracking"), "tracking");
  EXPECT_THROW_WITH(t.load(r), DataError, "another camera");
  TrackerParams tp = trackerParams(*d);
  tp.orb.features = 1000;
  Tracker t2(d->cam, tp);
  StateReader r2(stageStatePath(map, "tracking"), "tracking");
  EXPECT_THROW_WITH(t2.load(r2), DataError, "descriptors come from");
  TrackerParams learned = trackerParams(*d);  // the same settings but the other BRIEF tests
  learned.orb.pattern = BriefPatternKind::kOrbLearned;
  Tracker t3(d->cam, learned);
  StateReader r3(stageStatePath(map, "tracking"), "tracking");
  EXPECT_THROW_WITH(
      t3.load(r3), DataError,
      "the map's descriptors come from binloop ORB with the Gaussian BRIEF pattern (2000 features");
}
