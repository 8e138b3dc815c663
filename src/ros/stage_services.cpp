#include "binloop_ros/stage_services.h"

#include <ros/console.h>

#include <filesystem>

#include "binloop/io/map_folder.h"

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
  res.map_id = req.map_id ? req.map_id : binloop::newMapId();
  answer(
      "saved", "not saved",
      [&] {
        if (req.directory.empty()) throw std::invalid_argument("no directory given");
        std::filesystem::create_directories(req.directory);
        const std::string path = binloop::stageStatePath(req.directory, stage_);
        const std::string what = h_.save(path, res.map_id);
        return what + ", " + std::to_string(std::filesystem::file_size(path) >> 20) + " MB";
      },
      res);
  return true;
}

bool StageServices::onLoad(binloop::LoadMap::Request& req, binloop::LoadMap::Response& res) {
  const std::string& phase = req.phase;
  if (phase == "commit" || phase == "abort") {
    answer(
        phase == "commit" ? "loaded" : "load aborted", "not loaded",
        [&] {
          if (!pending_ || pending_->map_id != req.map_id)
            throw std::invalid_argument("no load of map save " + binloop::mapIdText(req.map_id) +
                                        " prepared");
          const Pending p = std::move(*pending_);
          pending_.reset();
          res.map_id = p.map_id;
          return phase == "commit" ? p.load.commit()
                                   : std::string("the prepared load dropped, the running map stays");
        },
        res);
    return true;
  }
  answer(
      phase.empty() ? "loaded" : "load prepared", "not loaded, the running map stays",
      [&] {
        if (!phase.empty() && phase != "prepare")
          throw std::invalid_argument("phase '" + phase + "': give \"\", prepare, commit or abort");
        if (req.directory.empty()) throw std::invalid_argument("no directory given");
        pending_.reset();
        const std::string path = binloop::stageStatePath(req.directory, stage_);
        res.map_id = binloop::stateFileMapId(path, stage_);
        if (req.map_id && res.map_id != req.map_id)
          throw binloop::mixedSaveError(path, res.map_id, "the other stages' files", req.map_id);
        PreparedLoad load = h_.prepare(path);
        if (phase.empty()) return load.commit();
        pending_ = Pending{res.map_id, std::move(load)};
        return std::string("checked and loaded aside (map save ") + binloop::mapIdText(res.map_id) + ")";
      },
      res);
  return true;
}

bool StageServices::onReset(binloop::Reset::Request&, binloop::Reset::Response& res) {
  answer(
      "reset", "not reset",
      [&] {
        h_.reset();
        return std::string("reset");
      },
      res);
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
