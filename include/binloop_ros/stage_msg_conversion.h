#pragma once
// Every conversion between the stage messages of the core (include/binloop/messages/) and their ROS
// messages (msg/), both ways, tested in test/ros/stage_msg_conversion_test.cpp. The nodelets never touch a
// field themselves. Field for field; the only changes are representation: poses as geometry_msgs/Pose,
// descriptors as bytes, stamps as ros::Time. Messages from outside are checked (sizes that must agree,
// ids that must not be 0) and refused with ConversionError naming the field.
#include <binloop/Correction.h>
#include <binloop/KeyFrame.h>
#include <binloop/LocalMapUpdate.h>
#include <binloop/LoopCandidates.h>
#include <binloop/LoopClosure.h>
#include <binloop/TrackedFrame.h>

#include "binloop/messages/correction.h"
#include "binloop/messages/keyframe.h"
#include "binloop/messages/local_map_update.h"
#include "binloop/messages/loop_candidates.h"
#include "binloop/messages/loop_closure.h"
#include "binloop/messages/tracked_frame.h"
#include "binloop_ros/msg_conversion.h"

namespace binloop_ros {

/// `frame_id` names the map frame. The stamp is the keyframe's (KeyFrame::stamp_s).
binloop::KeyFrame toRos(const binloop::msg::KeyFrame& kf, const std::string& frame_id);
binloop::msg::KeyFrame fromRos(const binloop::KeyFrame& m);

/// The core update carries no stamp: the caller gives the keyframe's.
binloop::LocalMapUpdate toRos(const binloop::msg::LocalMapUpdate& u, const std_msgs::Header& header);
binloop::msg::LocalMapUpdate fromRos(const binloop::LocalMapUpdate& m);

binloop::LoopCandidates toRos(const binloop::msg::LoopCandidates& c, const std_msgs::Header& header);
binloop::msg::LoopCandidates fromRos(const binloop::LoopCandidates& m);

binloop::LoopClosure toRos(const binloop::msg::LoopClosure& c, const std_msgs::Header& header);
binloop::msg::LoopClosure fromRos(const binloop::LoopClosure& m);

binloop::Correction toRos(const binloop::msg::Correction& c, const std_msgs::Header& header);
binloop::msg::Correction fromRos(const binloop::Correction& m);

/// `frame_id` names the map frame. The stamp is the frame's (TrackedFrame::stamp_s).
binloop::TrackedFrame toRos(const binloop::msg::TrackedFrame& f, const std::string& frame_id);
binloop::msg::TrackedFrame fromRos(const binloop::TrackedFrame& m);

}  // namespace binloop_ros
