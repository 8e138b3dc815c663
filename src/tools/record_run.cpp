// record-run: listens to a running binloop graph and, when stopped (SIGINT/SIGTERM), writes the offline
// runner's files from what the graph published, so the ROS path and `run` can be compared file for file:
// trajectory.kitti.txt / .tum.txt (every tracked pair, each on its reference keyframe's final pose),
// keyframes.kitti.txt, loops.csv and summary.json. Used by scripts/binloop run-bag.
#include <binloop/LocalMapUpdate.h>
#include <binloop/LoopCandidates.h>
#include <binloop/LoopClosure.h>
#include <binloop/TrackedFrame.h>
#include <diagnostic_msgs/DiagnosticArray.h>
#include <ros/ros.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>

#include "binloop/io/trajectory_io.h"
#include "binloop/pipeline/final_trajectory.h"
#include "binloop/pipeline/loop_log.h"
#include "binloop/util/cli_args.h"
#include "binloop/util/json_object.h"
#include "binloop/util/percentile.h"
#include "binloop_ros/stage_msg_conversion.h"

using namespace binloop;
namespace fs = std::filesystem;

namespace {

volatile std::sig_atomic_t g_stop = 0;

void onSignal(int) { g_stop = 1; }

struct Recorder {
  std::vector<msg::TrackedFrame> frames;
  struct Kf {
    Pose3 T_w_c = Pose3::Identity();
    bool culled = false;
  };
  std::map<SlamKeyframeId, Kf> keyframes;
  std::vector<SlamPipeline::LoopLogEntry> loops;
  std::map<SlamKeyframeId, size_t> loop_entry;  // query keyframe -> its entry
  ros::WallTime last_message = ros::WallTime::now();

  std::map<std::string, std::map<std::string, std::string>> diagnostics;  // the last of each status
  std::vector<double> latency_ms;  // image stamp -> tracked frame received (ROS time: the bag's clock)
  std::vector<double> track_ms;    // extraction + stereo + tracking, per pair

  void onDiagnostics(const diagnostic_msgs::DiagnosticArrayConstPtr& m) {
    for (const auto& st : m->status) {
      auto& d = diagnostics[st.name];
      d["summary"] = st.message;
      for (const auto& kv : st.values) d[kv.key] = kv.value;
    }
  }

  void onFrame(const binloop::TrackedFrameConstPtr& m) {
    latency_ms.push_back((ros::Time::now() - m->header.stamp).toSec() * 1e3);
    track_ms.push_back(m->extract_ms + m->stereo_ms + m->track_ms);
    frames.push_back(binloop_ros::fromRos(*m));
    last_message = ros::WallTime::now();
  }
  void onUpdate(const binloop::LocalMapUpdateConstPtr& m) {
    const msg::LocalMapUpdate u = binloop_ros::fromRos(*m);
    for (const auto& s : u.keyframes) {
      Kf& k = keyframes[s.id];
      k.T_w_c = s.T_w_c;
    }
    for (SlamKeyframeId id : u.culled_keyframes) keyframes[id].culled = true;
    last_message = ros::WallTime::now();
  }
  SlamPipeline::LoopLogEntry& entryOf(SlamKeyframeId q) {
    auto it = loop_entry.find(q);
    if (it != loop_entry.end()) return loops[it->second];
    loop_entry[q] = loops.size();
    loops.emplace_back();
    return loops.back();
  }
  void onCandidates(const binloop::LoopCandidatesConstPtr& m) {
    auto c = std::make_shared<const msg::LoopCandidates>(binloop_ros::fromRos(*m));
    last_message = ros::WallTime::now();
    auto& e = entryOf(c->query);
    if (c->shadow)
      e.shadow.push_back(c);
    else
      e.active = c;
  }
  void onClosure(const binloop::LoopClosureConstPtr& m) {
    auto c = std::make_shared<const msg::LoopClosure>(binloop_ros::fromRos(*m));
    last_message = ros::WallTime::now();
    entryOf(c->query).closures.push_back(c);
  }

  // A culled keyframe keeps the last pose mapping sent for it. (The offline runner moves it with its parent's
  // later corrections; frames on such keyframes may differ by what a correction after the culling moved.)
  bool poseOf(SlamKeyframeId id, Pose3* T) const {
    auto it = keyframes.find(id);
    if (it == keyframes.end()) return false;
    *T = it->second.T_w_c;
    return true;
  }

  void write(const fs::path& out) const {
    fs::create_directories(out);
    writeTrajectoryFiles(
        (out / "trajectory").string(),
        finalTrajectory(frames, [this](SlamKeyframeId id, Pose3* T) { return poseOf(id, T); }));
    size_t lost = 0;
    for (const msg::TrackedFrame& f : frames) lost += f.state == msg::TrackingState::kLost;
    std::vector<Pose3> kf_poses;
    size_t live = 0;
    for (const auto& [id, k] : keyframes)
      if (!k.culled) {
        kf_poses.push_back(k.T_w_c);
        ++live;
      }
    writeKittiPoses((out / "keyframes.kitti.txt").string(), kf_poses);
    writeLoopLog((out / "loops.csv").string(), loops);
    std::map<std::string, int> by_status;
    for (const auto& e : loops)
      for (const auto& c : e.closures) ++by_status[msg::loopStatusName(c->status)];
    JsonObject statuses, diagnostic_values(true);
    for (const auto& [status, n] : by_status) statuses.add(status, n);
    for (const auto& [name, values] : diagnostics) {
      JsonObject d;
      for (const auto& [k, v] : values) d.add(k, v);
      diagnostic_values.add(name, d);
    }
    JsonObject js;
    js.add("source", "ros graph (record-run)").add("frames", frames.size()).add("lost_frames", lost);
    js.add("keyframes", live).add("loops_by_status", statuses);
    js.add("latency_ms_median", percentile(latency_ms, 0.5))
        .add("latency_ms_p95", percentile(latency_ms, 0.95));
    js.add("tracking_ms_median", percentile(track_ms, 0.5))
        .add("tracking_ms_p95", percentile(track_ms, 0.95));
    js.add("diagnostics", diagnostic_values);
    std::ofstream(out / "summary.json") << js.str();
  }
};

}  // namespace

int main(int argc, char** argv) {
  CliArgs args("record-run",
               "usage: record-run --out <dir> [--ns /binloop]\n"
               "Records what a running binloop graph publishes; on SIGINT/SIGTERM writes "
               "trajectory.kitti.txt/.tum.txt,\n"
               "keyframes.kitti.txt, loops.csv and summary.json into <dir> (the offline runner's files).");
  args.option("out", "folder to write")
      .option("ns", "namespace of the graph's topics", "/binloop")
      .option("quiet-s", "after the stop signal, write once the graph has published nothing for this long",
              "3");
  return runTool("record-run", [&] {
    if (!args.parse(argc, argv)) return 0;
    if (!args.has("out")) throw CliError("--out is required");
    ros::init(argc, argv, "record_run",
              ros::init_options::NoSigintHandler | ros::init_options::AnonymousName);
    std::signal(SIGINT, onSignal);
    std::signal(SIGTERM, onSignal);
    ros::NodeHandle nh(args.str("ns"));
    Recorder r;
    auto subs = {nh.subscribe("tracked_frame", 10000, &Recorder::onFrame, &r),
                 nh.subscribe("local_map_update", 10000, &Recorder::onUpdate, &r),
                 nh.subscribe("loop_candidates", 10000, &Recorder::onCandidates, &r),
                 nh.subscribe("loop_closure", 10000, &Recorder::onClosure, &r),
                 nh.subscribe("/diagnostics", 1000, &Recorder::onDiagnostics, &r)};
    while (!g_stop && ros::ok()) {
      ros::spinOnce();
      ros::WallDuration(0.01).sleep();
    }
    // Asked to stop (the bag has played): the graph may still be working through queued pairs and loops, so
    // wait until it has been quiet for --quiet-s seconds.
    const double quiet = std::stod(args.str("quiet-s"));
    while (ros::ok() && (ros::WallTime::now() - r.last_message).toSec() < quiet) {
      ros::spinOnce();
      ros::WallDuration(0.01).sleep();
    }
    r.write(args.str("out"));
    std::cerr << "record-run: " << r.frames.size() << " frames, " << r.keyframes.size() << " keyframes -> "
              << args.str("out") << "\n";
    return 0;
  });
}
