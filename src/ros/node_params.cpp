#include "binloop_ros/node_params.h"

#include <algorithm>

#include "binloop_ros/msg_conversion.h"

namespace binloop_ros {

std::vector<std::string> unknownParams(const ros::NodeHandle& pnh, const std::vector<std::string>& known) {
  std::vector<std::string> all;
  ros::param::getParamNames(all);
  const std::string prefix = pnh.getNamespace() + "/";
  std::vector<std::string> out;
  for (const std::string& name : all) {
    if (name.compare(0, prefix.size(), prefix) != 0) continue;
    std::string rel = name.substr(prefix.size());
    rel = rel.substr(0, rel.find('/'));  // a nested key belongs to its top-level parameter
    if (std::find(known.begin(), known.end(), rel) == known.end() &&
        std::find(out.begin(), out.end(), rel) == out.end())
      out.push_back(rel);
  }
  return out;
}

void requireKnownParams(const ros::NodeHandle& pnh, const std::vector<std::string>& known) {
  const auto unknown = unknownParams(pnh, known);
  if (unknown.empty()) return;
  std::string text = "unknown parameter(s) under " + pnh.getNamespace() + ":";
  for (const auto& u : unknown) text += " " + u;
  text += "; known:";
  for (const auto& k : known) text += " " + k;
  throw ConversionError(text);
}

binloop::SlamConfig slamConfigFrom(const ros::NodeHandle& pnh) {
  const std::string path = stringParam(pnh, "config", "");
  return path.empty() ? binloop::SlamConfig{} : binloop::loadSlamConfig(path);
}

std::string stringParam(const ros::NodeHandle& pnh, const std::string& name, const std::string& fallback) {
  if (!pnh.hasParam(name)) return fallback;
  std::string v;
  if (!pnh.getParam(name, v)) throw ConversionError("parameter ~" + name + " must be a string");
  return v;
}

double numberParam(const ros::NodeHandle& pnh, const std::string& name, double fallback) {
  if (!pnh.hasParam(name)) return fallback;
  double v = 0;
  if (pnh.getParam(name, v)) return v;
  int i = 0;
  if (pnh.getParam(name, i)) return i;
  throw ConversionError("parameter ~" + name + " must be a number");
}

bool boolParam(const ros::NodeHandle& pnh, const std::string& name, bool fallback) {
  if (!pnh.hasParam(name)) return fallback;
  bool v = false;
  if (!pnh.getParam(name, v)) throw ConversionError("parameter ~" + name + " must be true or false");
  return v;
}

std::optional<binloop::Pose3> poseParam(const ros::NodeHandle& pnh, const std::string& name) {
  if (!pnh.hasParam(name)) return std::nullopt;
  std::vector<double> v;
  if (!pnh.getParam(name, v) || v.size() != 7)
    throw ConversionError("~" + name + " must be a list of 7 numbers: x, y, z, qx, qy, qz, qw");
  geometry_msgs::Pose p;
  p.position.x = v[0];
  p.position.y = v[1];
  p.position.z = v[2];
  p.orientation.x = v[3];
  p.orientation.y = v[4];
  p.orientation.z = v[5];
  p.orientation.w = v[6];
  return toPose3(p);
}

}  // namespace binloop_ros
