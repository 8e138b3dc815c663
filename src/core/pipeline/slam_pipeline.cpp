#include "binloop/pipeline/slam_pipeline.h"

namespace binloop {

SlamPipeline::SlamPipeline(const StereoCamera& cam, const TrackerParams& tp, const LocalMapperParams& mp,
                           PipelineMode mode, size_t queue_capacity)
    : mode_(mode), tracker_(cam, tp), mapper_(mp), keyframes_(queue_capacity), updates_(1u << 20) {
  if (mode_ == PipelineMode::kThreaded) {
    mapping_thread_ = std::thread([this] {
      while (auto kf = keyframes_.pop()) map(*kf);
    });
  }
}

SlamPipeline::~SlamPipeline() { finish(); }

void SlamPipeline::map(const msg::KeyFramePtr& kf) {
  LocalMapper::Output out = mapper_.process(*kf);
  mapping_times_.push_back({kf->id, kf->frame_index, out.update->total_ms, out.update->ba_ms,
                            out.update->triangulation_ms, out.update->points_triangulated});
  if (on_keyframe) on_keyframe(out.refined);
  updates_.push(out.update);
  --pending_;
}

void SlamPipeline::drainUpdates() {
  while (auto u = updates_.tryPop()) tracker_.apply(**u);
}

msg::TrackedFrame SlamPipeline::process(const StereoFrame& frame) {
  drainUpdates();
  Tracker::Output out = tracker_.track(frame, pending_.load());
  if (out.keyframe) {
    ++pending_;
    if (mode_ == PipelineMode::kLockStep) {
      map(out.keyframe);
      drainUpdates();
    } else {
      // A keyframe waiting means the running local BA should stop early (ORB-SLAM2's abort flag).
      mapper_.abortFlag() = true;
      keyframes_.push(out.keyframe);
    }
  }
  return out.frame;
}

void SlamPipeline::finish() {
  if (finished_) return;
  finished_ = true;
  keyframes_.close();
  if (mapping_thread_.joinable()) mapping_thread_.join();
  drainUpdates();
}

}  // namespace binloop
