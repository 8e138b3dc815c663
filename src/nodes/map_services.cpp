// map_services: the graph-wide map services, /binloop/save_map, load_map, reset and statistics. Each stage
// owns its state and saves or loads only that (~save_state, ~load_state, ~reset, ~statistics of each nodelet,
// include/binloop_ros/stage_services.h); this node asks the stages in pipeline order, whether they share one
// manager or run in four processes, and answers with what each said. Save and load are transactions
// (binloop/io/map_folder.h): a save has every stage write into a new folder that replaces the old only when
// all have written; a load has every stage check and load its file aside, and puts them in place only when
// all could, so a refusal anywhere leaves the whole graph on its map.
//
// Parameters: ~stages (list, default [tracking, local_mapping, loop_detector, loop_closing]): the stages'
// node names, resolved in this node's namespace; ~timeout_s (default 120): how long one stage may take.
#include <binloop/LoadMap.h>
#include <binloop/Reset.h>
#include <binloop/SaveMap.h>
#include <binloop/Statistics.h>
#include <ros/ros.h>

#include "binloop/io/data_error.h"
#include "binloop/io/map_folder.h"

#include <string>
#include <type_traits>
#include <vector>

namespace {

std::vector<std::string> g_stages;
double g_timeout_s = 120;

void say(std::string* message, const std::string& line) { *message += (message->empty() ? "" : "\n") + line; }

enum class Reached { kNo, kCallFailed, kAnswered };

// Calls `service` of one stage with `srv`; the stage's answer (or why there is none) is added to `message`.
template <class Srv>
Reached callStage(const std::string& stage, const std::string& service, Srv& srv, std::string* message) {
  ros::NodeHandle nh;
  const std::string name = nh.resolveName(stage + "/" + service);
  if (!ros::service::waitForService(name, ros::Duration(g_timeout_s))) {
    say(message, stage + ": no service " + name + " (is the stage running?)");
    return Reached::kNo;
  }
  if (!nh.serviceClient<Srv>(name).call(srv)) {
    say(message, stage + ": " + name + " failed");
    return Reached::kCallFailed;
  }
  if constexpr (!std::is_same_v<Srv, binloop::Statistics>) say(message, srv.response.message);
  return Reached::kAnswered;
}

// Calls `service` of every stage in order; stops at the first that cannot be reached. `success` and `message`
// gather the stages' answers (services without them, such as Statistics, leave them as they are).
template <class Srv>
void callEach(const std::string& service, const typename Srv::Request& req, bool* success,
              std::string* message, std::vector<typename Srv::Response>* answers = nullptr) {
  *success = true;
  message->clear();
  for (const std::string& stage : g_stages) {
    Srv srv;
    srv.request = req;
    const Reached r = callStage(stage, service, srv, message);
    if (r != Reached::kAnswered) *success = false;
    if (r == Reached::kNo) return;
    if (r != Reached::kAnswered) continue;
    if (answers) answers->push_back(srv.response);
    if constexpr (!std::is_same_v<Srv, binloop::Statistics>) *success = *success && srv.response.success;
  }
}

// /binloop/<what>: every stage's `service`, with their answers joined.
template <class Srv>
auto forward(const std::string& what, const std::string& service) {
  return [what, service](typename Srv::Request& req, typename Srv::Response& res) {
    bool ok = false;
    callEach<Srv>(service, req, &ok, &res.message);
    res.success = ok;
    ROS_INFO("binloop/map_services: %s: %s\n%s", what.c_str(), ok ? "done" : "FAILED", res.message.c_str());
    return true;
  };
}

// Every stage writes into the save's staging folder, which replaces `directory` only when all have.
bool onSaveMap(binloop::SaveMap::Request& req, binloop::SaveMap::Response& res) {
  bool ok = false;
  try {
    binloop::MapSave save(req.directory, req.map_id ? req.map_id : binloop::newMapId());
    binloop::SaveMap::Request each;
    each.directory = save.staging();
    each.map_id = save.mapId();
    callEach<binloop::SaveMap>("save_state", each, &ok, &res.message);
    res.map_id = save.mapId();
    if (ok) save.commit();
  } catch (const std::exception& e) {
    ok = false;
    say(&res.message, e.what());
  }
  if (!ok) say(&res.message, "nothing saved: " + req.directory + " is as it was");
  res.success = ok;
  ROS_INFO("binloop/map_services: save_map %s (map save %s): %s\n%s", req.directory.c_str(),
           binloop::mapIdText(res.map_id).c_str(), ok ? "done" : "FAILED", res.message.c_str());
  return true;
}

// Every stage checks and loads its file aside (all of one save); then all commit, or all abort.
bool onLoadMap(binloop::LoadMap::Request& req, binloop::LoadMap::Response& res) {
  std::vector<std::string> prepared;
  bool ok = true;
  auto call = [&](const std::string& stage, binloop::LoadMap& srv) {
    return callStage(stage, "load_state", srv, &res.message) == Reached::kAnswered && srv.response.success;
  };
  uint64_t map_id = 0;
  for (const std::string& stage : g_stages) {
    binloop::LoadMap srv;
    srv.request.directory = req.directory;
    srv.request.phase = "prepare";
    srv.request.map_id = map_id;  // the first stage's file names the save; the others must be of it too
    if (!call(stage, srv)) {
      ok = false;
      break;
    }
    if (prepared.empty()) map_id = srv.response.map_id;
    prepared.push_back(stage);
  }
  const std::string phase = ok ? "commit" : "abort";  // the same for every prepared stage
  for (const std::string& stage : prepared) {
    binloop::LoadMap srv;
    srv.request.phase = phase;
    srv.request.map_id = map_id;
    if (!call(stage, srv)) ok = false;  // a commit cannot fail but for a stage gone meanwhile
  }
  if (!ok && prepared.size() < g_stages.size())
    say(&res.message, "nothing loaded: every stage keeps its map");
  res.success = ok;
  res.map_id = map_id;
  ROS_INFO("binloop/map_services: load_map %s (map save %s): %s\n%s", req.directory.c_str(),
           binloop::mapIdText(map_id).c_str(), ok ? "done" : "FAILED", res.message.c_str());
  return true;
}

bool onStatistics(binloop::Statistics::Request& req, binloop::Statistics::Response& res) {
  bool ok = true;
  std::string message;
  std::vector<binloop::Statistics::Response> answers;
  callEach<binloop::Statistics>("statistics", req, &ok, &message, &answers);
  for (const auto& a : answers) res.values.insert(res.values.end(), a.values.begin(), a.values.end());
  if (!ok) ROS_WARN("binloop/map_services: statistics: %s", message.c_str());
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "map_services");
  ros::NodeHandle nh, pnh("~");
  g_stages = {"tracking", "local_mapping", "loop_detector", "loop_closing"};
  pnh.getParam("stages", g_stages);
  pnh.getParam("timeout_s", g_timeout_s);
  ros::ServiceServer save = nh.advertiseService("save_map", onSaveMap);
  ros::ServiceServer load = nh.advertiseService("load_map", onLoadMap);
  ros::ServiceServer reset = nh.advertiseService<binloop::Reset::Request, binloop::Reset::Response>(
      "reset", forward<binloop::Reset>("reset", "reset"));
  ros::ServiceServer stats = nh.advertiseService("statistics", onStatistics);
  // Services call other services: more than one thread, so a statistics request can be answered while a
  // long save waits on a stage.
  ros::AsyncSpinner spinner(2);
  spinner.start();
  ros::waitForShutdown();
  return 0;
}
