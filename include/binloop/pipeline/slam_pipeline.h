#pragma once
// The stages wired in one process, for the offline runner and the tests. Two modes:
// - lock-step: each keyframe is mapped, searched for loops and any correction applied before the next
//   frame is tracked, so a run depends only on its input (bit-identical reruns);
// - threaded: local mapping and the loop stages (detection, then closing) each on their own thread behind
//   queues, tracking on the caller's; updates reach tracking when they are ready, as between nodelets.
// Stages only exchange the messages of messages/*.h; this class owns the queues between them.
//
// Threads: everything belongs to one caller thread, except switchDetector() (any thread: it only records
// the switch) and, in threaded mode, addExternalLoop() (any thread: it only queues). In threaded mode each
// stage object is touched by its own thread alone, and mapper() and the logs are read only after finish().
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <variant>

#include "binloop/loop/loop_closer.h"
#include "binloop/loop/loop_detector.h"
#include "binloop/mapping/local_mapper.h"
#include "binloop/pipeline/bounded_queue.h"
#include "binloop/pipeline/pipeline_params.h"
#include "binloop/tracking/tracker.h"

namespace binloop {

/// Loop closing, when wanted: the detector's settings and how it makes models, the closer's settings,
/// shadow models, and switches of the active model at given keyframe counts.
struct LoopClosingSetup {
  LoopDetectorParams detector;
  LoopDetector::ModelFactory make_model;
  LoopCloserParams closer;
  std::vector<std::string> shadow;
  std::vector<std::pair<size_t, std::string>> switches;  // (keyframes seen by the detector, model)
  LoopDetector::ModelIdentity model_identity;            // vocabularies a saved map records (model_files.h)
};

class SlamPipeline {
 public:
  /// Throws PlaceError when loop closing's first model, a shadow model or a model named in `switches`
  /// cannot be made.
  SlamPipeline(const StereoCamera& cam, const TrackerParams& tp, const LocalMapperParams& mp,
               const PipelineParams& pp, std::optional<LoopClosingSetup> loops = std::nullopt);
  ~SlamPipeline();
  SlamPipeline(const SlamPipeline&) = delete;
  SlamPipeline& operator=(const SlamPipeline&) = delete;

  /// Tracks one frame (on the caller's thread). Never throws for bad input (see Tracker::track).
  /// `due`: the wall time the frame was due by its clock, when the caller paces frames (the runner at a
  /// rate); the wait for mapping (`wait_for_mapping_ms`) ends that long after it. Without it (flat out,
  /// the tests) every frame may wait the whole allowance.
  msg::TrackedFrame process(const StereoFrame& frame,
                            std::optional<std::chrono::steady_clock::time_point> due = std::nullopt);
  /// Waits until every stage has processed everything sent to it and tracking has applied every update.
  void finish();

  /// The input's clock started again (a bag replayed): Tracker::restartClock. From the caller of process().
  void restartClock() { tracker_.restartClock(); }
  /// Where the camera is, from outside (Tracker::hintPose). From the caller of process().
  void hintPose(const Pose3& T_w_c, double radius_m) { tracker_.hintPose(T_w_c, radius_m); }

  /// The model loop detection uses from its next keyframe on (any thread). Throws PlaceError for a model
  /// that cannot be made; the running one stays.
  void switchDetector(const std::string& model);

  /// Writes every stage's state into `directory`, one file per stage as the ROS map services do
  /// (io/state_file.h, stageStatePath), as one transaction (io/map_folder.h: a new folder swapped in for the
  /// old); returns the save's map id. In lock-step, or after finish(). Throws DataError, and `directory` is
  /// then as it was.
  uint64_t saveMap(const std::string& directory) const;
  /// Loads a map saved by saveMap (or the ROS save_map service) into this new pipeline, before its first
  /// frame: tracking then relocalises in it and the loop stages search and correct it. Throws DataError
  /// (a missing or broken file, another camera, extractor or vocabulary), and the pipeline must then be
  /// discarded. Every stage's file is checked to be of one save before any is read; returns its map id.
  uint64_t loadMap(const std::string& directory);
  /// The stages that save state: tracking, local_mapping, and with loop closing loop_detector, loop_closing.
  std::vector<std::string> stageNames() const;

  /// A loop between two keyframes from outside (another front end, a person), verified and guarded like a
  /// detected one by loop closing, on its thread, after what it has queued; the outcome appears in the loop
  /// log with model `source`. Throws PlaceError when loop closing is off.
  void addExternalLoop(SlamKeyframeId query, SlamKeyframeId match, const std::string& source = "external");

  /// Called on the mapping thread with each refined keyframe; set before the first frame.
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

  /// Per keyframe searched for loops: what each model proposed and what loop closing made of it.
  struct LoopLogEntry {
    msg::LoopCandidatesPtr active;
    std::vector<msg::LoopCandidatesPtr> shadow;
    std::vector<msg::LoopClosurePtr> closures;
    double correction_ms = 0;  // local mapping applying an accepted loop's correction (lock-step only)
    double global_ba_ms =
        0;  // ... of which the global BA, when on (lock-step only; threaded: mapper().globalBaStats())
    double switch_ms = 0;  // rebuilding a newly switched model's index before this query
    std::string problem;   // a switch that failed (the running model stayed), empty otherwise
  };
  /// Only once finish() has returned.
  const std::vector<LoopLogEntry>& loopLog() const { return loop_log_; }
  bool closesLoops() const { return detector_ != nullptr; }

 private:
  using MappingInput = std::variant<msg::KeyFramePtr, msg::CorrectionPtr>;
  struct ExternalLoop {
    SlamKeyframeId query, match;
    std::string source;
  };
  struct LoopInput {
    msg::KeyFramePtr refined;  // null for an update alone or an external loop
    msg::LocalMapUpdatePtr update;
    std::optional<ExternalLoop> external;
  };
  void sendCorrection(const msg::CorrectionPtr& c);
  /// A map update from mapping to tracking and loop closing (on the loop thread's queue while it runs).
  void sendMapUpdate(const msg::LocalMapUpdatePtr& u, bool loop_thread_running);
  void mergeGlobalBa(bool wait, bool loop_thread_running);
  void map(const MappingInput& in);
  void searchLoops(const LoopInput& in);
  void drainUpdates();
  /// Until mapping has processed every keyframe sent (pending_ 0), or until `deadline` when one is given.
  void waitUntilMappingIdle(std::optional<std::chrono::steady_clock::time_point> deadline);
  /// Calls f(name, stage) for each stage that runs, in the order stageNames() lists them.
  template <class Self, class F>
  static void forEachStage(Self& self, F&& f);

  PipelineParams params_;
  Tracker tracker_;
  LocalMapper mapper_;
  std::unique_ptr<LoopDetector> detector_;
  std::unique_ptr<LoopCloser> closer_;
  std::vector<std::pair<size_t, std::string>> switches_;
  LoopDetector::ModelFactory make_model_;
  std::mutex switch_mutex_;
  std::string switch_to_;  // set by switchDetector, taken by the loop thread
  BoundedQueue<MappingInput> mapping_inbox_;
  BoundedQueue<LoopInput> loop_inbox_;
  BoundedQueue<msg::LocalMapUpdatePtr> updates_;
  std::atomic<int> pending_{0};  // keyframes sent to mapping and not yet processed
  std::mutex idle_mutex_;        // with idle_: map() tells waiters that pending_ went down
  std::condition_variable idle_;
  std::vector<MappingTime> mapping_times_;
  std::vector<LoopLogEntry> loop_log_;
  double last_correction_ba_ms_ = 0;
  std::thread mapping_thread_, loop_thread_;
  bool finished_ = false;
};

}  // namespace binloop
