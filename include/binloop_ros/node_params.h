#pragma once
// What every nodelet does with its private parameters: refuse names it does not know (a typo in a launch
// file would otherwise silently keep a default) and load the SLAM settings from the same commented YAML file
// the offline runner reads, so both paths run with one configuration.
#include <ros/node_handle.h>
#include <ros/param.h>

#include <optional>
#include <string>
#include <vector>

#include "binloop/pipeline/slam_config.h"
#include "binloop/types/pose.h"

namespace binloop_ros {

/// Private parameters (relative names) that are not in `known`; dynamic_reconfigure's are ignored when
/// `known` holds them.
std::vector<std::string> unknownParams(const ros::NodeHandle& pnh, const std::vector<std::string>& known);
/// Throws ConversionError listing them; call first in onInit().
void requireKnownParams(const ros::NodeHandle& pnh, const std::vector<std::string>& known);

/// The file ~config names (default: none, the built-in defaults). Throws binloop::ConfigError.
binloop::SlamConfig slamConfigFrom(const ros::NodeHandle& pnh);

/// ~name as a string / number, or `fallback` when unset; a value of another type is a ConversionError.
std::string stringParam(const ros::NodeHandle& pnh, const std::string& name, const std::string& fallback);
double numberParam(const ros::NodeHandle& pnh, const std::string& name, double fallback);
bool boolParam(const ros::NodeHandle& pnh, const std::string& name, bool fallback);
/// ~name as a pose [x, y, z, qx, qy, qz, qw], or nothing when unset; another shape or a zero quaternion is a
/// ConversionError.
std::optional<binloop::Pose3> poseParam(const ros::NodeHandle& pnh, const std::string& name);

}  // namespace binloop_ros
