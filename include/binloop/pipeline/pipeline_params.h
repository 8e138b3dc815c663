#pragma once
// How the offline pipeline (SlamPipeline: `run`, `eval-slam`, the tests) runs its stages together. The
// settings file's `pipeline` section gives wait_for_mapping_ms; the runner sets the mode from its
// options. The ROS graph runs each stage in its own nodelet and reads none of it.
#include <cstddef>

namespace binloop {

enum class PipelineMode { kLockStep, kThreaded };

struct PipelineParams {
  // Implicit on purpose: most callers only choose the mode.
  PipelineParams(PipelineMode m = PipelineMode::kLockStep) : mode(m) {}

  PipelineMode mode;
  size_t queue_capacity = 3;  // keyframes queued for mapping before tracking blocks (threaded)
  // Threaded: before tracking a frame, wait for local mapping to finish the keyframes sent to it, so the
  // frame is tracked against the map lock-step would give it, as long as tracking stays within this many ms
  // of the frames' clock. While the machine keeps up, runs at a camera's pace then repeat each other instead
  // of depending on which thread won; when mapping takes longer, tracking goes on against the map as it
  // stands, as without the wait. 0: never wait. The frames' clock is the caller's (SlamPipeline::process's
  // `due`).
  double wait_for_mapping_ms = 0;
};

}  // namespace binloop
