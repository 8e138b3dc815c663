#pragma once
// The stages wired in one process, for the offline runner and the tests. Two modes:
// - lock-step: each keyframe is mapped and its update applied before the next frame is tracked, so a run
//   depends only on its input (bit-identical reruns);
// - threaded: local mapping on its own thread behind a bounded queue, tracking on the caller's; updates
//   reach tracking when they are ready, as between nodelets.
// Stages only exchange the messages of messages/*.h; this class owns the queues between them.
#include <functional>
#include <memory>
#include <thread>

#include "binloop/mapping/local_mapper.h"
#include "binloop/pipeline/bounded_queue.h"
#include "binloop/tracking/tracker.h"

namespace binloop {

enum class PipelineMode { kLockStep, kThreaded };

class SlamPipeline {
 public:
  SlamPipeline(const StereoCamera& cam, const TrackerParams& tp, const LocalMapperParams& mp, PipelineMode mode,
               size_t queue_capacity = 3);
  ~SlamPipeline();
  SlamPipeline(const SlamPipeline&) = delete;
  SlamPipeline& operator=(const SlamPipeline&) = delete;

  /// Tracks one frame (on the caller's thread). Never throws for bad input (see Tracker::track).
  msg::TrackedFrame process(const StereoFrame& frame);
  /// Waits until mapping has processed every keyframe and tracking has applied every update.
  void finish();

  /// Called on the mapping thread with each refined keyframe (the loop stages' input); set before the
  /// first frame.
  std::function<void(const msg::KeyFramePtr&)> on_keyframe;

  const Tracker& tracker() const { return tracker_; }
  /// Only once finish() has returned (in threaded mode the mapper belongs to its thread until then).
  const LocalMapper& mapper() const { return mapper_; }
  /// Per mapped keyframe: (keyframe, total ms, local BA ms), in processing order.
  struct MappingTime {
    SlamKeyframeId keyframe;
    uint64_t frame_index;
    double total_ms, ba_ms, triangulation_ms;
    int points_triangulated;
  };
  const std::vector<MappingTime>& mappingTimes() const { return mapping_times_; }

 private:
  void map(const msg::KeyFramePtr& kf);
  void drainUpdates();

  PipelineMode mode_;
  Tracker tracker_;
  LocalMapper mapper_;
  BoundedQueue<msg::KeyFramePtr> keyframes_;
  BoundedQueue<msg::LocalMapUpdatePtr> updates_;
  std::atomic<int> pending_{0};  // keyframes sent to mapping and not yet processed
  std::vector<MappingTime> mapping_times_;
  std::thread mapping_thread_;
  bool finished_ = false;
};

}  // namespace binloop
