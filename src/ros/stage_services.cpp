#include "binloop_ros/stage_services.h"

#include <ros/console.h>

#include <filesystem>

namespace binloop_ros {

StageServices::StageServices(ros::NodeHandle& pnh, std::string stage, StageServiceHandlers h)
    : stage_(std::move(stage)), h_(std::move(h)) {
  save_ = pnh.advertiseService("save_state", &StageServices::onSave, this);
  load_ = pnh.advertiseService("load_state", &StageServices::onLoad, this);
  reset_ = pnh.advertiseService("reset", &StageServices::onReset, this);
  statistics_ = pnh.advertiseService("statistics", &StageServices::onStatistics, this);
}

std::string StageServices::statePath(const std::string& directory, const std::string& stage) {
  return binloop::stageStatePath(directory, stage);
}

bool StageServices::onSave(binloop::SaveMap::Request& req, binloop::SaveMap::Response& res) {
  try {
    if (req.directory.empty()) throw std::invalid_argument("no directory given");
    std::filesystem::create_directories(req.directory);
    res.message = stage_ + ": " + h_.save(statePath(req.directory, stage_));
    res.success = true;
    ROS_INFO("binloop/%s: saved: %s", stage_.c_str(), res.message.c_str());
  } catch (const std::exception& e) {
    res.success = false;
    res.message = stage_ + ": not saved: " + e.what();
    ROS_ERROR("binloop/%s", res.message.c_str());
  }
  return true;
}

bool StageServices::onLoad(binloop::LoadMap::Request& req, binloop::LoadMap::Response& res) {
  try {
    if (req.directory.empty()) throw std::invalid_argument("no directory given");
    res.message = stage_ + ": " + h_.load(statePath(req.directory, stage_));
    res.success = true;
    ROS_INFO("binloop/%s: loaded: %s", stage_.c_str(), res.message.c_str());
  } catch (const std::exception& e) {
    res.success = false;
    res.message = stage_ + ": not loaded, the running map stays: " + e.what();
    ROS_ERROR("binloop/%s", res.message.c_str());
  }
  return true;
}

bool StageServices::onReset(binloop::Reset::Request&, binloop::Reset::Response& res) {
  try {
    h_.reset();
    res.success = true;
    res.message = stage_ + ": reset";
    ROS_INFO("binloop/%s: reset", stage_.c_str());
  } catch (const std::exception& e) {
    res.success = false;
    res.message = stage_ + ": not reset: " + e.what();
    ROS_ERROR("binloop/%s", res.message.c_str());
  }
  return true;
}

bool StageServices::onStatistics(binloop::Statistics::Request&, binloop::Statistics::Response& res) {
  for (const auto& [k, v] : h_.statistics()) {
    diagnostic_msgs::KeyValue kv;
    kv.key = stage_ + "/" + k;
    kv.value = v;
    res.values.push_back(kv);
  }
  return true;
}

}  // namespace binloop_ros
