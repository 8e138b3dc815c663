#pragma once
// A small hbow vocabulary (1000 words: k = 10, 3 levels) trained by a test on every `step`-th left image of
// frames [from, to), with the extractor settings the SLAM runs: the tests need a vocabulary, not a good one,
// and the shipped one (vocab/kitti08/hbow.bin, 26 MB) is not in the repository.
#include <string>
#include <vector>

#include "binloop/features/orb_slam_extractor.h"
#include "binloop/place/model_training.h"
#include "binloop/tracking/frame.h"

namespace binloop::test {

inline void trainSmallHbow(const std::vector<StereoFrame>& frames, size_t from, size_t to, size_t step,
                           const std::string& path) {
  const OrbSlamParams orb;
  OrbSlamExtractor ex(orb);
  std::vector<Descriptors> images;
  for (size_t i = from; i < to && i < frames.size(); i += step)
    images.push_back(ex.extract(frames[i].left).descriptors);
  TrainOptions o;
  o.k = 10;
  o.levels = 3;
  o.extractor = extractorSettings(orb, 0);
  trainModel(ModelType::kHbow, images, o, path);
}

}  // namespace binloop::test
