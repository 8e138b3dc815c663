// map_services: the graph-wide map services, /binloop/save_map, load_map, reset and statistics. Each stage owns
// its state and saves or loads only that (~save_state, ~load_state, ~reset, ~statistics of each nodelet,
// include/binloop_ros/stage_services.h); this node asks the stages in pipeline order, whether they share one
// manager or run in four processes, and answers with what each said. A stage that refuses a load keeps its
// map, so the answer names the stages that did and did not load.
//
// Parameters: ~stages (list, default [tracking, local_mapping, loop_detector, loop_closing]): the stages'
// node names, resolved in this node's namespace; ~timeout_s (default 120): how long one stage may take.
#include <binloop/LoadMap.h>
#include <binloop/Reset.h>
#include <binloop/SaveMap.h>
#include <binloop/Statistics.h>
#include <ros/ros.h>

#include <string>
#include <type_traits>
#include <vector>

namespace {

std::vector<std::string> g_stages;
double g_timeout_s = 120;

// Calls `service` of every stage in order; stops at the first that cannot be reached. `success` and `message`
// gather the stages' answers (services without them, such as Statistics, leave them as they are).
template <class Srv>
void callEach(const std::string& service, const typename Srv::Request& req, bool* success, std::string* message,
              std::vector<typename Srv::Response>* answers = nullptr) {
  *success = true;
  message->clear();
  auto say = [&](const std::string& line) { *message += (message->empty() ? "" : "\n") + line; };
  ros::NodeHandle nh;
  for (const std::string& stage : g_stages) {
    const std::string name = nh.resolveName(stage + "/" + service);
    if (!ros::service::waitForService(name, ros::Duration(g_timeout_s))) {
      *success = false;
      return say(stage + ": no service " + name + " (is the stage running?)");
    }
    Srv srv;
    srv.request = req;
    if (!nh.serviceClient<Srv>(name).call(srv)) {
      *success = false;
      say(stage + ": " + name + " failed");
      continue;
    }
    if (answers) answers->push_back(srv.response);
    if constexpr (!std::is_same_v<Srv, binloop::Statistics>) {
      *success = *success && srv.response.success;
      say(srv.response.message);
    }
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
  ros::ServiceServer save = nh.advertiseService<binloop::SaveMap::Request, binloop::SaveMap::Response>(
      "save_map", forward<binloop::SaveMap>("save_map", "save_state"));
  ros::ServiceServer load = nh.advertiseService<binloop::LoadMap::Request, binloop::LoadMap::Response>(
      "load_map", forward<binloop::LoadMap>("load_map", "load_state"));
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
