#pragma once
// A rendered drive of 1.25 laps round a 50 x 80 m block (the built-in route; no data files needed), made once
// per test program, with a small hbow vocabulary (1000 words) trained on every 10th frame of the first lap:
// the loop-closing and map save/load tests drive the SLAM over it.
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "binloop/features/orb_slam_extractor.h"
#include "binloop/loop/loop_detector.h"
#include "binloop/pipeline/slam_pipeline.h"
#include "binloop/place/model_training.h"
#include "binloop/sim/builtin_route.h"
#include "binloop/sim/stereo_renderer.h"
#include "binloop/sim/texture_bank.h"
#include "binloop/tracking/frame.h"
#include "small_vocabulary.h"
#include "support/test_support.h"

namespace binloop::test {

struct LoopDrive {
  std::vector<Pose3> route;
  std::vector<StereoFrame> frames;
  StereoCamera cam = kittiCameraByName("kitti04");
  std::unique_ptr<test::TempDir> dir;
  std::string vocabulary;
  size_t lap = 0;  // frames in one lap
};

/// Null when the texture photos are missing (the tests then skip and say so).
inline const LoopDrive* loopDrive() {
  static std::unique_ptr<LoopDrive> d;
  if (d) return d.get();
  const std::vector<std::string> photos = sim::defaultTexturePhotos();
  for (const auto& p : photos)
    if (!std::filesystem::exists(p)) return nullptr;
  d = std::make_unique<LoopDrive>();
  d->route = sim::loopRoute(50, 80, 12, 8, 10, 1.25);
  d->lap = static_cast<size_t>(d->route.size() / 1.25);
  const auto world = sim::World::build(d->route, sim::TextureBank::build(photos, 1), {}, 1);
  sim::StereoRenderer r(world, d->cam, {}, 1);
  d->frames = sim::renderFrames(r, d->route, 0, d->route.size());
  d->dir = std::make_unique<test::TempDir>();
  d->vocabulary = *d->dir / "hbow.bin";
  trainSmallHbow(d->frames, 0, d->lap, 10, d->vocabulary);
  return d.get();
}

/// Makes any model from the drive's vocabulary (hbow is the only model trained here).
inline LoopDetector::ModelFactory tinyVocabularyFactory(const LoopDrive& d) {
  const std::string voc = d.vocabulary;
  return [voc](const std::string& name) {
    RecognizerOptions ro;
    ro.model_file = voc;
    return makePlaceRecognizer(name, ro);
  };
}

/// Loop closing with the drive's tiny vocabulary as the hbow model (the product's default model is another).
inline LoopClosingSetup tinyHbowLoopSetup(const LoopDrive& d) {
  LoopClosingSetup l;
  l.detector.model = "hbow";
  l.make_model = tinyVocabularyFactory(d);
  return l;
}

}  // namespace binloop::test
