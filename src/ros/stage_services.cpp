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

template <class Response>
void StageServices::answer(const char* done, const char* failed, const std::function<std::string()>& act,
                           Response& res) {
  try {
    res.message = stage_ + ": " + act();
    res.success = true;
    ROS_INFO("binloop/%s: %s: %s", stage_.c_str(), done, res.message.c_str());
  } catch (const std::exception& e) {
    res.success = false;
    res.message = stage_ + ": " + failed + ": " + e.what();
    ROS_ERROR("binloop/%s", res.message.c_str());
  }
}

bool StageServices::onSave(binloop::SaveMap::Request& req, binloop::SaveMap::Response& res) {
  answer("saved", "not saved", [&] {
    if (req.directory.empty()) throw std::invalid_argument("no directory given");
    std::filesystem::create_directories(req.directory);
    const std::string path = binloop::stageStatePath(req.directory, stage_);
    const std::string what = h_.save(path);
    return what + ", " + std::to_string(std::filesystem::file_size(path) >> 20) + " MB";
  }, res);
  return true;
}

bool StageServices::onLoad(binloop::LoadMap::Request& req, binloop::LoadMap::Response& res) {
  answer("loaded", "not loaded, the running map stays", [&] {
    if (req.directory.empty()) throw std::invalid_argument("no directory given");
    return h_.load(binloop::stageStatePath(req.directory, stage_));
  }, res);
  return true;
}

bool StageServices::onReset(binloop::Reset::Request&, binloop::Reset::Response& res) {
  answer("reset", "not reset", [&] {
    h_.reset();
    return std::string("reset");
  }, res);
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
