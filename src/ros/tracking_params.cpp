#include "binloop_ros/tracking_params.h"

#include <algorithm>

#include "binloop/pipeline/model_files.h"
#include "binloop/util/package_paths.h"
#include "binloop_ros/frame_publisher.h"
#include "binloop_ros/node_params.h"
#include "binloop_ros/topics.h"

namespace binloop_ros {

TrackingParams TrackingParams::read(const ros::NodeHandle& pnh) {
  std::vector<std::string> known = {"config",
                                    "reloc_vocab",
                                    "force_extractor",
                                    "sync",
                                    "queue_size",
                                    "max_stamp_diff",
                                    "camera_frame",
                                    "camera",
                                    "seed",
                                    "lockstep",
                                    "max_time_jump",
                                    "transport",
                                    "stereo",
                                    "time_jump_confirm_pairs",
                                    "stale_after_s",
                                    "path_max_poses",
                                    "keyframe_timeout_s",
                                    "localize_only"};
  known.insert(known.end(), FramePublisher::parameterNames().begin(), FramePublisher::parameterNames().end());
  requireKnownParams(pnh, known);
  TrackingParams p;
  p.keyframe_timeout_s = numberParam(pnh, "keyframe_timeout_s", 5);
  p.stamps = StampGateParams{numberParam(pnh, "max_time_jump", 5),
                             static_cast<int>(numberParam(pnh, "time_jump_confirm_pairs", 3))};
  p.stale_after_s = numberParam(pnh, "stale_after_s", 2);
  p.path_max_poses = static_cast<size_t>(std::max(1.0, numberParam(pnh, "path_max_poses", 1000)));
  p.config = slamConfigFrom(pnh);
  if (p.config.pipeline.wait_for_mapping_ms > 0) {
    ROS_WARN(
        "binloop/Tracking: pipeline.wait_for_mapping_ms is for the runner (run, eval-slam) and is ignored "
        "here; ~lockstep holds pairs while keyframes are in flight");
  }
  p.config.tracker.seed = static_cast<uint64_t>(numberParam(pnh, "seed", 1));
  p.config.tracker.localize_only = boolParam(pnh, "localize_only", p.config.tracker.localize_only);
  // "" or "none": relocalisation tries only the most recent keyframes.
  const std::string reloc =
      binloop::relocVocabFor(stringParam(pnh, "reloc_vocab", binloop::kAutoVocab),
                             p.config.tracker.orb.pattern == binloop::BriefPatternKind::kOrbLearned);
  if (!reloc.empty() && reloc != "none") {
    p.config.tracker.vocabulary = binloop::loadRelocalisationVocabulary(
        reloc, p.config.tracker.orb, boolParam(pnh, "force_extractor", false));
    p.config.tracker.vocabulary_identity = binloop::modelFileIdentity(reloc);
  }
  if (pnh.hasParam("camera")) {  // calibration from YAML (rosparam) instead of camera_info
    binloop::StereoCamera cam;
    cam.fx = numberParam(pnh, "camera/fx", 0);
    cam.fy = numberParam(pnh, "camera/fy", 0);
    cam.cx = numberParam(pnh, "camera/cx", 0);
    cam.cy = numberParam(pnh, "camera/cy", 0);
    cam.baseline_m = numberParam(pnh, "camera/baseline", 0);
    cam.width = static_cast<int>(numberParam(pnh, "camera/width", 0));
    cam.height = static_cast<int>(numberParam(pnh, "camera/height", 0));
    p.camera = cam;
  }
  p.camera_frame = stringParam(pnh, "camera_frame", "");
  p.max_stamp_diff = numberParam(pnh, "max_stamp_diff", 0.002);
  p.lockstep = boolParam(pnh, "lockstep", false);
  p.queue_size = static_cast<int>(numberParam(pnh, "queue_size", 5));
  p.sync = stringParam(pnh, "sync", "exact");
  p.transport = stringParam(pnh, "transport", "raw");
  p.stereo = stringParam(pnh, "stereo", topics::kStereoNamespace);
  return p;
}

}  // namespace binloop_ros
