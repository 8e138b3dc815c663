#pragma once
// The SLAM's settings as one value, loaded from a commented YAML file (config/kitti.yaml) or left at the
// defaults the parameter structs carry. Loading is strict: an unknown section or key, a missing file, a
// value that is not a number or out of its range is a ConfigError naming the file and the key.
#include <stdexcept>
#include <string>

#include "binloop/loop/loop_closer.h"
#include "binloop/loop/loop_detector.h"
#include "binloop/mapping/local_mapper.h"
#include "binloop/pipeline/pipeline_params.h"
#include "binloop/tracking/tracker.h"

namespace binloop {

class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct SlamConfig {
  TrackerParams tracker;
  LocalMapperParams mapper;
  LoopDetectorParams detector;  // its `model` comes from the runner's --detector, not from the file
  LoopCloserParams closer;
  // The place models' thresholds (file loop_detection section); model_file and the extractor check are set
  // where a model is loaded.
  RecognizerOptions models;
  // The offline pipeline (file section `pipeline`); its mode comes from the runner's options (the pace
  // reaches `process` as `due`).
  PipelineParams pipeline;
};

/// Keys the file gives override the defaults; keys it leaves out keep them.
SlamConfig loadSlamConfig(const std::string& path);
/// "section.key: value" lines of every setting, for logs and summary.json.
std::string describe(const SlamConfig& c);

}  // namespace binloop
