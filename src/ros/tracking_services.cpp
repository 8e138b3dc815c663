#include "binloop_ros/tracking_services.h"

#include <stdexcept>

#include "binloop/io/state_file.h"

namespace binloop_ros {

StageServiceHandlers trackingServiceHandlers(binloop::TrackingStage& stage, const TrackingStatus& status,
                                             std::function<void()> started_over) {
  auto counts = [&stage] {
    const binloop::Tracker& t = *stage.tracker();
    return std::to_string(t.map().keyframeCount()) + " keyframes, " + std::to_string(t.map().pointCount()) +
           " map points";
  };
  StageServiceHandlers h;
  h.save = [&stage, counts](const std::string& path, uint64_t map_id) {
    if (!stage.tracker()) throw std::runtime_error("tracking has no camera yet, so no map");
    binloop::saveStateFile(*stage.tracker(), path, "tracking", map_id);
    return counts() + " in its replica";
  };
  h.prepare = [&stage, counts, started_over](const std::string& path) {
    // Without a camera yet, the map's own: the first camera_info must then agree with it (image sizes are
    // checked).
    const binloop::Tracker* t = stage.tracker();
    auto fresh = std::make_shared<std::unique_ptr<binloop::Tracker>>(loadStage(
        stage.freshTracker(t ? t->camera() : binloop::Tracker::savedCamera(path)), path, "tracking"));
    return PreparedLoad{[&stage, fresh, counts, started_over] {
      stage.startOver(std::move(*fresh));
      started_over();
      return counts() + "; lost until the next frames are relocalised";
    }};
  };
  h.reset = [&stage, started_over] {
    stage.reset();
    started_over();
  };
  h.statistics = [&stage, &status] {
    StageStatistics s{{"frames", std::to_string(status.frames)},
                      {"frames_lost", std::to_string(status.lost)},
                      {"input_dropped", std::to_string(status.rejected)},
                      {"keyframes_sent", std::to_string(status.keyframes_sent)}};
    if (const binloop::Tracker* t = stage.tracker()) {
      s.emplace_back("state", binloop::msg::toString(t->state()));
      s.emplace_back("keyframes", std::to_string(t->map().keyframeCount()));
      s.emplace_back("map_points", std::to_string(t->map().pointCount()));
    }
    return s;
  };
  return h;
}

}  // namespace binloop_ros
