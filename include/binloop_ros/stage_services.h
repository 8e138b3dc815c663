#pragma once
// The map services each stage nodelet offers in its private namespace: ~save_state, ~load_state, ~reset and
// ~statistics (srv/). The nodelet gives what its stage does for each; this class owns the service servers,
// turns exceptions into an answer (success false, the reason), and logs. /binloop/save_map and the other
// graph-wide services (src/nodes/map_services.cpp) call these, one stage after another; a graph-wide load
// is a transaction, so this class holds a load prepared aside until it is committed or aborted.
#include <binloop/LoadMap.h>
#include <binloop/Reset.h>
#include <binloop/SaveMap.h>
#include <binloop/Statistics.h>
#include <ros/node_handle.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "binloop/io/state_file.h"

namespace binloop_ros {

using StageStatistics = std::vector<std::pair<std::string, std::string>>;

/// A stage loaded from its file but not yet in place: `commit` puts it in place of the running one and says
/// what it holds.
struct PreparedLoad {
  std::function<std::string()> commit;
};

struct StageServiceHandlers {
  /// Writes the stage's file at the path given, for map save `map_id`; returns a one-line summary (the
  /// file's size is added to it). Throws on failure.
  std::function<std::string(const std::string& path, uint64_t map_id)> save;
  /// Loads the stage's file into a new stage, changing nothing that runs (throws when it cannot).
  std::function<PreparedLoad(const std::string& path)> prepare;
  std::function<void()> reset;
  std::function<StageStatistics()> statistics;
};

/// Loads `path` into `fresh` (a newly made stage) and returns it, so that the running stage is replaced only
/// when the load worked (binloop::loadStateFile throws otherwise).
template <class Stage>
std::unique_ptr<Stage> loadStage(std::unique_ptr<Stage> fresh, const std::string& path,
                                 const std::string& name) {
  binloop::loadStateFile(*fresh, path, name);
  return fresh;
}

class StageServices {
 public:
  /// `stage` names the file (binloop::stageStatePath) and prefixes the statistics.
  StageServices(ros::NodeHandle& pnh, std::string stage, StageServiceHandlers h);

 private:
  /// Runs `act` (which returns what was done) and answers success and message, logged as "<done>: ..."; an
  /// exception is the answer "<stage>: <failed>: <why>".
  template <class Response>
  void answer(const char* done, const char* failed, const std::function<std::string()>& act, Response& res);
  bool onSave(binloop::SaveMap::Request& req, binloop::SaveMap::Response& res);
  bool onLoad(binloop::LoadMap::Request& req, binloop::LoadMap::Response& res);
  bool onReset(binloop::Reset::Request& req, binloop::Reset::Response& res);
  bool onStatistics(binloop::Statistics::Request& req, binloop::Statistics::Response& res);

  struct Pending {
    uint64_t map_id;
    PreparedLoad load;
  };

  std::string stage_;
  StageServiceHandlers h_;
  std::optional<Pending> pending_;  // a load prepared aside (phase "prepare")
  ros::ServiceServer save_, load_, reset_, statistics_;
};

}  // namespace binloop_ros
