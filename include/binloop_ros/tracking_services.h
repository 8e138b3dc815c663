#pragma once
// The Tracking stage's part in the graph-wide map services (save_state / load_state / reset / statistics,
// stage_services.h): its tracker's map replica saved and loaded, a reset, its counts.
#include <functional>
#include <memory>

#include "binloop/tracking/tracking_stage.h"
#include "binloop_ros/stage_services.h"
#include "binloop_ros/tracking_status.h"

namespace binloop_ros {

/// `started_over` is called after the stage's tracker was replaced by a load or a reset (what the nodelet
/// keeps of the old tracker's frames goes). `stage` and `status` must outlive the handlers.
StageServiceHandlers trackingServiceHandlers(binloop::TrackingStage& stage, const TrackingStatus& status,
                                             std::function<void()> started_over);

}  // namespace binloop_ros
