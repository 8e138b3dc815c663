#include "binloop/pipeline/slam_pipeline.h"

#include <algorithm>
#include <chrono>
#include <filesystem>

#include "binloop/io/filesystem.h"
#include "binloop/io/map_folder.h"
#include "binloop/io/state_file.h"

namespace binloop {

SlamPipeline::SlamPipeline(const StereoCamera& cam, const TrackerParams& tp, const LocalMapperParams& mp,
                           const PipelineParams& pp, std::optional<LoopClosingSetup> loops)
    : params_(pp),
      tracker_(cam, tp),
      mapper_([&] {
        LocalMapperParams m = mp;  // threaded, a global BA runs beside mapping (lock-step: in it)
        m.global_ba_in_background = pp.mode == PipelineMode::kThreaded;
        return m;
      }()),
      mapping_inbox_(pp.queue_capacity),
      loop_inbox_(1u << 20),
      updates_(1u << 20) {
  if (loops) {
    detector_ = std::make_unique<LoopDetector>(loops->detector, loops->make_model);
    if (loops->model_identity) detector_->setModelIdentity(loops->model_identity);
    if (!loops->shadow.empty()) detector_->setShadowModels(loops->shadow);
    closer_ = std::make_unique<LoopCloser>(loops->closer);
    switches_ = loops->switches;
    make_model_ = loops->make_model;
    for (const auto& [at, model] : switches_) make_model_(model);  // a bad file fails now, not mid-run
  }
  if (params_.mode == PipelineMode::kThreaded) {
    mapping_thread_ = std::thread([this] {
      while (auto in = mapping_inbox_.pop()) map(*in);
    });
    if (detector_) {
      loop_thread_ = std::thread([this] {
        while (auto in = loop_inbox_.pop()) searchLoops(*in);
      });
    }
  }
}

SlamPipeline::~SlamPipeline() { finish(); }

template <class Self, class F>
void SlamPipeline::forEachStage(Self& self, F&& f) {
  f("tracking", self.tracker_);
  f("local_mapping", self.mapper_);
  if (self.detector_) f("loop_detector", *self.detector_);
  if (self.closer_) f("loop_closing", *self.closer_);
}

std::vector<std::string> SlamPipeline::stageNames() const {
  std::vector<std::string> stages;
  forEachStage(*this, [&](const char* name, const auto&) { stages.emplace_back(name); });
  return stages;
}

uint64_t SlamPipeline::saveMap(const std::string& directory) const {
  MapSave save(directory);
  forEachStage(*this, [&](const char* name, const auto& stage) {
    saveStateFile(stage, stageStatePath(save.staging(), name), name, save.mapId());
  });
  save.commit();
  return save.mapId();
}

uint64_t SlamPipeline::loadMap(const std::string& directory) {
  requireDirectory(directory);
  if (detector_ && !std::filesystem::exists(stageStatePath(directory, "loop_detector"))) {
    throw dataError(directory, 0,
                    "the map has no loop_detector.state (saved without loop closing): load it with "
                    "loop closing off (--detector none)");
  }
  const uint64_t map_id = checkMapFolder(directory, stageNames());
  forEachStage(*this, [&](const char* name, auto& stage) {
    loadStateFile(stage, stageStatePath(directory, name), name);
  });
  return map_id;
}

void SlamPipeline::switchDetector(const std::string& model) {
  if (!detector_) throw PlaceError("loop closing is off: no detector to switch");
  make_model_(model);  // throws now for a model that cannot be made; the loop stage makes its own
  std::lock_guard<std::mutex> lk(switch_mutex_);
  switch_to_ = model;
}

void SlamPipeline::addExternalLoop(SlamKeyframeId query, SlamKeyframeId match, const std::string& source) {
  if (!closer_) throw PlaceError("loop closing is off: no external loop can be added");
  LoopInput in;
  in.external = ExternalLoop{query, match, source};
  if (params_.mode == PipelineMode::kLockStep) {
    searchLoops(in);
  } else {
    loop_inbox_.push(in);
  }
}

void SlamPipeline::sendCorrection(const msg::CorrectionPtr& c) {
  if (params_.mode == PipelineMode::kLockStep) {
    const auto t0 = std::chrono::steady_clock::now();
    map(c);
    loop_log_.back().correction_ms = msSince(t0);
    loop_log_.back().global_ba_ms = last_correction_ba_ms_;
    drainUpdates();  // tracking holds the corrected map before the next frame
  } else {
    mapping_inbox_.push(c);
  }
}

void SlamPipeline::sendMapUpdate(const msg::LocalMapUpdatePtr& u, bool loop_thread_running) {
  updates_.push(u);
  if (!closer_) return;
  if (params_.mode == PipelineMode::kThreaded && loop_thread_running) {
    loop_inbox_.push({nullptr, u, std::nullopt});
  } else {
    closer_->apply(*u);  // what it would send again is ignored here: in one process no correction is lost
  }
}

void SlamPipeline::mergeGlobalBa(bool wait, bool loop_thread_running) {
  if (msg::LocalMapUpdatePtr u = mapper_.mergeGlobalBa(wait)) sendMapUpdate(u, loop_thread_running);
}

void SlamPipeline::map(const MappingInput& in) {
  if (const auto* c = std::get_if<msg::CorrectionPtr>(&in)) {
    mapper_.abortFlag() = false;  // a keyframe that comes from now on cuts a foreground global BA short
    msg::LocalMapUpdatePtr u = mapper_.apply(**c);
    if (!u) return;  // applied already
    last_correction_ba_ms_ = u->ba_ms;
    sendMapUpdate(u, true);
    return;
  }
  mergeGlobalBa(false, true);  // one that finished since the last input goes out first
  const msg::KeyFramePtr& kf = std::get<msg::KeyFramePtr>(in);
  mapper_.abortFlag() = false;  // a keyframe that comes from now on cuts this one's local BA short
  LocalMapper::Output out = mapper_.process(*kf);
  mapping_times_.push_back({kf->id, kf->frame_index, out.update->total_ms, out.update->ba_ms,
                            out.update->triangulation_ms, out.update->points_triangulated});
  if (on_keyframe) on_keyframe(out.refined);
  updates_.push(out.update);
  {
    std::lock_guard<std::mutex> lk(idle_mutex_);  // a waiter cannot miss the change between test and wait
    --pending_;
  }
  idle_.notify_all();
  if (!detector_) return;
  if (params_.mode == PipelineMode::kLockStep) {
    searchLoops({out.refined, out.update, std::nullopt});
  } else {
    loop_inbox_.push({out.refined, out.update, std::nullopt});
  }
}

void SlamPipeline::searchLoops(const LoopInput& in) {
  if (in.external) {
    LoopCloser::Output c =
        closer_->addExternalLoop(in.external->query, in.external->match, in.external->source);
    LoopLogEntry entry;
    entry.closures = c.closures;
    loop_log_.push_back(entry);
    if (c.correction) sendCorrection(c.correction);
    return;
  }
  if (!in.refined) {  // an update alone (the corrected map)
    closer_->apply(*in.update);
    return;
  }
  closer_->addKeyframe(in.refined);
  closer_->apply(*in.update);
  LoopLogEntry entry;
  std::string to;
  {
    std::lock_guard<std::mutex> lk(switch_mutex_);
    std::swap(to, switch_to_);
  }
  for (const auto& [at, model] : switches_)
    if (at == detector_->keyframeCount()) to = model;
  if (!to.empty() && to != detector_->activeModel()) {
    try {
      detector_->switchModel(to);
    } catch (const PlaceError& e) {  // checked when asked for; a file that went bad since is reported
      entry.problem =
          std::string("switch to ") + to + " failed, " + detector_->activeModel() + " stays: " + e.what();
    }
  }
  LoopDetector::Output d = detector_->process(*in.refined);
  entry.switch_ms = d.switch_ms;
  entry.active = d.active;
  entry.shadow = d.shadow;
  if (d.active) {
    LoopCloser::Output c = closer_->process(*d.active);
    entry.closures = c.closures;
    loop_log_.push_back(entry);
    if (c.correction) sendCorrection(c.correction);
  } else {
    loop_log_.push_back(entry);
  }
}

void SlamPipeline::drainUpdates() {
  while (auto u = updates_.tryPop()) tracker_.apply(**u);
}

void SlamPipeline::waitUntilMappingIdle(std::optional<std::chrono::steady_clock::time_point> deadline) {
  std::unique_lock<std::mutex> lk(idle_mutex_);
  const auto idle = [this] { return pending_.load() == 0; };
  if (deadline) {
    idle_.wait_until(lk, *deadline, idle);
  } else {
    idle_.wait(lk, idle);
  }
}

msg::TrackedFrame SlamPipeline::process(const StereoFrame& frame,
                                        std::optional<std::chrono::steady_clock::time_point> due) {
  if (params_.mode == PipelineMode::kThreaded && params_.wait_for_mapping_ms > 0) {
    // Within wait_for_mapping_ms of the frame's due time (loading it included): a frame that comes late
    // waits less, or not at all; one that comes early no longer than the allowance.
    const auto allowance = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double, std::milli>(params_.wait_for_mapping_ms));
    const auto now = std::chrono::steady_clock::now();
    waitUntilMappingIdle(std::min(due.value_or(now), now) + allowance);
  }
  const auto applying = std::chrono::steady_clock::now();
  drainUpdates();
  const double apply_ms = msSince(applying);
  Tracker::Output out = tracker_.track(frame, pending_.load());
  out.frame.apply_ms = apply_ms;
  if (out.keyframe) {
    ++pending_;
    if (params_.mode == PipelineMode::kLockStep) {
      map(out.keyframe);
      drainUpdates();
    } else {
      // A keyframe waiting means the running local BA should stop early (ORB-SLAM2's abort flag).
      mapper_.abortFlag() = true;
      mapping_inbox_.push(out.keyframe);
    }
  }
  return out.frame;
}

void SlamPipeline::finish() {
  if (finished_) return;
  finished_ = true;
  if (params_.mode == PipelineMode::kThreaded) {
    // Mapping first finishes its keyframes, then the loop stages their queue (a correction they send still
    // reaches mapping), then mapping whatever came back.
    waitUntilMappingIdle(std::nullopt);
    loop_inbox_.close();
    if (loop_thread_.joinable()) loop_thread_.join();
    mapping_inbox_.close();
    if (mapping_thread_.joinable()) mapping_thread_.join();
    mergeGlobalBa(true, false);  // the last loop's global BA, waited for
  }
  if (closer_) {  // a loop still held gets its final status in the log
    LoopCloser::Output c = closer_->finish();
    if (!c.closures.empty()) {
      LoopLogEntry entry;
      entry.closures = c.closures;
      loop_log_.push_back(entry);
    }
  }
  drainUpdates();
}

}  // namespace binloop
