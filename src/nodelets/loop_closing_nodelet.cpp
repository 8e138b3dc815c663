// binloop/LoopClosing: refined keyframes, local-map updates and the active model's LoopCandidates in; a
// LoopClosure per verified loop, the Correction for local mapping, the corrected keyframe path and the loop
// edges (markers coloured by status) out; the add_external_loop service. A short onInit() over
// binloop::LoopCloser. Across processes the candidates for a keyframe may overtake the keyframe or its
// update, so they wait here until both have arrived.
#include <binloop/AddExternalLoop.h>
#include <nav_msgs/Path.h>
#include <nodelet/nodelet.h>
#include <visualization_msgs/MarkerArray.h>
#include <algorithm>
#include <pluginlib/class_list_macros.hpp>

#include <memory>
#include <unordered_map>

#include "binloop/loop/candidate_gate.h"
#include "binloop/loop/loop_closer.h"
#include "binloop_ros/callback_guard.h"
#include "binloop_ros/cpu_meter.h"
#include "binloop_ros/node_params.h"
#include "binloop_ros/stage_diagnostics.h"
#include "binloop_ros/stage_msg_conversion.h"
#include "binloop_ros/stage_services.h"

namespace binloop_ros {

class LoopClosingNodelet : public nodelet::Nodelet {
 public:
  void onInit() override;

 private:
  void onKeyframe(const binloop::KeyFrameConstPtr& m);
  void onUpdate(const binloop::LocalMapUpdateConstPtr& m);
  void onCandidates(const binloop::LoopCandidatesConstPtr& m);
  bool onExternalLoop(binloop::AddExternalLoop::Request& req, binloop::AddExternalLoop::Response& res);
  void runPending();
  void handle(const binloop::LoopCloser::Output& out, const std_msgs::Header& header);
  void sendAgain(const std::vector<binloop::msg::CorrectionPtr>& again, bool gap,
                 const std_msgs::Header& header);
  void publishPathAndEdges(const ros::Time& stamp);
  void problem(const std::string& what);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& s);

  void startOver(std::unique_ptr<binloop::LoopCloser> c);
  StageServiceHandlers serviceHandlers();
  std::string counts() const;

  binloop::LoopCloserParams params_;
  std::unique_ptr<binloop::LoopCloser> closer_;
  std::unique_ptr<StageServices> services_;
  CallbackGuard guard_{"LoopClosing"};
  std::string slam_frame_;
  ros::Subscriber keyframe_sub_, update_sub_, candidates_sub_;
  ros::Publisher correction_pub_, closure_pub_, path_pub_, edges_pub_;
  ros::ServiceServer external_srv_;
  std::unique_ptr<StageDiagnostics> diag_;
  CpuMeter cpu_;
  binloop::CandidateGate<binloop::LoopCandidatesConstPtr> pending_;
  struct Edge {
    binloop::SlamKeyframeId query, match;
    binloop::msg::LoopStatus status;
  };
  std::vector<Edge> edges_;
  uint64_t verified_ = 0, accepted_ = 0, rejected_input_ = 0;
  std::map<std::string, uint64_t> by_status_;
  std::string last_problem_, last_loop_;
};

void LoopClosingNodelet::onInit() {
  ros::NodeHandle& nh = getNodeHandle();
  ros::NodeHandle& pnh = getPrivateNodeHandle();
  try {
    requireKnownParams(pnh, {"config", "slam_frame", "seed"});
    binloop::SlamConfig config = slamConfigFrom(pnh);
    config.closer.verify.seed = static_cast<uint64_t>(numberParam(pnh, "seed", 1));
    params_ = config.closer;
    closer_ = std::make_unique<binloop::LoopCloser>(params_);
  } catch (const std::exception& e) {
    NODELET_FATAL("binloop/LoopClosing: %s", e.what());
    throw;
  }
  slam_frame_ = stringParam(pnh, "slam_frame", "slam");  // tracking publishes map -> slam
  correction_pub_ = nh.advertise<binloop::Correction>("correction", binloop::CorrectionOutbox::kKept + 10);
  closure_pub_ = nh.advertise<binloop::LoopClosure>("loop_closure", 100);
  path_pub_ = nh.advertise<nav_msgs::Path>("corrected_path", 1, true);
  edges_pub_ = nh.advertise<visualization_msgs::MarkerArray>("loop_edges", 1, true);
  keyframe_sub_ = guard_.subscribe(nh, "refined_keyframe", 1000, &LoopClosingNodelet::onKeyframe, this);
  update_sub_ = guard_.subscribe(nh, "local_map_update", 1000, &LoopClosingNodelet::onUpdate, this);
  candidates_sub_ = guard_.subscribe(nh, "loop_candidates", 1000, &LoopClosingNodelet::onCandidates, this);
  external_srv_ = nh.advertiseService<binloop::AddExternalLoop::Request, binloop::AddExternalLoop::Response>(
      "add_external_loop",
      [this](binloop::AddExternalLoop::Request& req, binloop::AddExternalLoop::Response& res) {
        return guard_.run("add_external_loop",
                          [&] { onExternalLoop(req, res); });  // false: the caller sees a failed call
      });
  diag_ = std::make_unique<StageDiagnostics>(
      nh, pnh, "loop closing", [this](diagnostic_updater::DiagnosticStatusWrapper& s) { diagnose(s); });
  services_ = std::make_unique<StageServices>(pnh, "loop_closing", serviceHandlers());
}

// The stage's part in the graph-wide map services (stage_services.h).
StageServiceHandlers LoopClosingNodelet::serviceHandlers() {
  StageServiceHandlers h;
  h.save = [this](const std::string& path, uint64_t map_id) {
    binloop::saveStateFile(*closer_, path, "loop_closing", map_id);
    return counts();
  };
  h.prepare = [this](const std::string& path) {
    auto fresh = std::make_shared<std::unique_ptr<binloop::LoopCloser>>(
        loadStage(std::make_unique<binloop::LoopCloser>(params_), path, "loop_closing"));
    return PreparedLoad{[this, fresh] {
      startOver(std::move(*fresh));
      return counts();
    }};
  };
  h.reset = [this] { startOver(std::make_unique<binloop::LoopCloser>(params_)); };
  h.statistics = [this] {
    return StageStatistics{{"keyframes", std::to_string(closer_->keyframeCount())},
                           {"loops", std::to_string(closer_->loops().size())},
                           {"corrections", std::to_string(closer_->correctionsMade())},
                           {"corrections_resent", std::to_string(closer_->correctionsResent())},
                           {"loops_verified", std::to_string(verified_)}};
  };
  return h;
}

// A loaded map or a reset: what the nodelet kept of the old closer's input goes; a loaded map's loops show.
void LoopClosingNodelet::startOver(std::unique_ptr<binloop::LoopCloser> c) {
  std_msgs::Header h;
  h.stamp = ros::Time::now();
  handle(closer_->finish(), h);  // a loop the old map held is reported as it goes
  closer_ = std::move(c);
  pending_.clear();
  edges_.clear();
  for (const auto& e : closer_->loops())
    edges_.push_back({e.query, e.candidate, binloop::msg::LoopStatus::kAccepted});
  publishPathAndEdges(ros::Time::now());
}

std::string LoopClosingNodelet::counts() const {
  return std::to_string(closer_->keyframeCount()) + " keyframes, " + std::to_string(closer_->loops().size()) +
         " loops closed";
}

void LoopClosingNodelet::problem(const std::string& what) {
  ++rejected_input_;
  last_problem_ = what;
  NODELET_WARN_THROTTLE(1.0, "binloop/LoopClosing: %s", what.c_str());
}

void LoopClosingNodelet::onKeyframe(const binloop::KeyFrameConstPtr& m) {
  CpuMeter::Scope cpu(cpu_);
  try {
    closer_->addKeyframe(std::make_shared<const binloop::msg::KeyFrame>(fromRos(*m)));
  } catch (const std::exception& e) {
    return problem(std::string("keyframe dropped: ") + e.what());
  }
  pending_.keyframeArrived(m->id);
  runPending();
}

void LoopClosingNodelet::onUpdate(const binloop::LocalMapUpdateConstPtr& m) {
  CpuMeter::Scope cpu(cpu_);
  std::vector<binloop::msg::CorrectionPtr> again;
  bool gap = false;
  try {
    again = closer_->apply(fromRos(*m), &gap);
  } catch (const std::exception& e) {
    return problem(std::string("local map update dropped: ") + e.what());
  }
  if (!again.empty()) sendAgain(again, gap, m->header);
  if (!m->correction)
    pending_.updateArrived(m->keyframe);
  else
    publishPathAndEdges(m->header.stamp);
  runPending();
}

void LoopClosingNodelet::onCandidates(const binloop::LoopCandidatesConstPtr& m) {
  CpuMeter::Scope cpu(cpu_);
  if (m->shadow) return;  // shadow models are logged, never acted on
  pending_.push(m->query, m);
  runPending();
}

void LoopClosingNodelet::runPending() {
  while (auto r = pending_.next()) {
    const binloop::LoopCandidatesConstPtr& m = r->candidates;
    if (!r->ready) {
      problem("loop candidates for keyframe " + std::to_string(m->query) +
              " dropped: the keyframe never arrived");
      continue;
    }
    try {
      handle(closer_->process(fromRos(*m)), m->header);
    } catch (const std::exception& e) {
      problem(std::string("loop candidates dropped: ") + e.what());
    }
  }
}

void LoopClosingNodelet::handle(const binloop::LoopCloser::Output& out, const std_msgs::Header& header) {
  std_msgs::Header h = header;
  h.frame_id = slam_frame_;
  for (const auto& c : out.closures) {
    ++verified_;
    ++by_status_[binloop::msg::loopStatusName(c->status)];
    // A held loop comes again with its final status: its edge changes colour instead of being drawn twice.
    auto same = std::find_if(edges_.begin(), edges_.end(),
                             [&](const auto& e) { return e.query == c->query && e.match == c->match; });
    if (same != edges_.end())
      same->status = c->status;
    else
      edges_.push_back({c->query, c->match, c->status});
    last_loop_ = c->model + " " + std::to_string(c->query_frame) + " -> " + std::to_string(c->match_frame) +
                 ": " + binloop::msg::loopStatusName(c->status) + " (" + c->detail + ")";
    NODELET_INFO("binloop/LoopClosing: loop %s", last_loop_.c_str());
    closure_pub_.publish(boost::make_shared<binloop::LoopClosure>(toRos(*c, h)));
  }
  if (out.correction) {
    ++accepted_;
    correction_pub_.publish(boost::make_shared<binloop::Correction>(toRos(*out.correction, h)));
  }
  if (!out.closures.empty()) publishPathAndEdges(header.stamp);
}

// Local mapping lacks corrections it was sent (correction_outbox.h): they go again, in sequence.
void LoopClosingNodelet::sendAgain(const std::vector<binloop::msg::CorrectionPtr>& again, bool gap,
                                   const std_msgs::Header& header) {
  std_msgs::Header h = header;
  h.frame_id = slam_frame_;
  NODELET_WARN(
      "binloop/LoopClosing: local mapping's updates still lack corrections %lu-%lu (it restarted, or "
      "one was lost on the way): sent again%s",
      static_cast<unsigned long>(again.front()->sequence), static_cast<unsigned long>(again.back()->sequence),
      gap ? "; it also lacks older ones, no longer kept, so it will refuse these" : "");
  if (gap) problem("local mapping lacks corrections no longer kept: it refuses every later one");
  for (const binloop::msg::CorrectionPtr& c : again)
    correction_pub_.publish(boost::make_shared<binloop::Correction>(toRos(*c, h)));
}

bool LoopClosingNodelet::onExternalLoop(binloop::AddExternalLoop::Request& req,
                                        binloop::AddExternalLoop::Response& res) {
  CpuMeter::Scope cpu(cpu_);
  const std::string source = req.source.empty() ? "external" : req.source;
  const binloop::LoopCloser::Output out = closer_->addExternalLoop(req.query, req.match, source);
  std_msgs::Header h;
  h.stamp = ros::Time::now();
  handle(out, h);
  res.accepted = out.correction != nullptr;
  for (const auto& c : out.closures) res.closures.push_back(toRos(*c, h));
  return true;
}

void LoopClosingNodelet::publishPathAndEdges(const ros::Time& stamp) {
  nav_msgs::Path path;
  path.header.stamp = stamp;
  path.header.frame_id = slam_frame_;
  std::unordered_map<binloop::SlamKeyframeId, Eigen::Vector3d> where;
  for (const auto& k : closer_->keyframePoses()) {
    geometry_msgs::PoseStamped p;
    p.header.stamp = stamp;
    p.header.frame_id = slam_frame_;
    p.pose = toPoseMsg(k.T_w_c);
    path.poses.push_back(p);
    where[k.id] = k.T_w_c.translation();
  }
  path_pub_.publish(path);

  visualization_msgs::MarkerArray edges;
  visualization_msgs::Marker line;
  line.header = path.header;
  line.ns = "loop_edges";
  line.type = visualization_msgs::Marker::LINE_LIST;
  line.action = visualization_msgs::Marker::ADD;
  line.pose.orientation.w = 1;
  line.scale.x = 0.5;
  for (const auto& e : edges_) {
    auto q = where.find(e.query), m = where.find(e.match);
    if (q == where.end() || m == where.end()) continue;
    std_msgs::ColorRGBA c;
    c.a = 1;
    using binloop::msg::LoopStatus;
    if (e.status == LoopStatus::kAccepted || e.status == LoopStatus::kAgreed)
      c.g = 1;  // green
    else if (e.status == LoopStatus::kHeld)
      c.r = c.g = 1;  // yellow
    else
      c.r = 1;  // red: rejected, whatever the reason
    for (const auto* p : {&q->second, &m->second}) {
      geometry_msgs::Point gp;
      gp.x = p->x();
      gp.y = p->y();
      gp.z = p->z();
      line.points.push_back(gp);
      line.colors.push_back(c);
    }
  }
  if (!line.points.empty()) edges.markers.push_back(line);
  edges_pub_.publish(edges);
}

void LoopClosingNodelet::diagnose(diagnostic_updater::DiagnosticStatusWrapper& s) {
  s.summary(rejected_input_ ? diagnostic_msgs::DiagnosticStatus::WARN : diagnostic_msgs::DiagnosticStatus::OK,
            rejected_input_ ? "closing loops; some input dropped" : "closing loops");
  s.add("keyframes", closer_->keyframeCount());
  s.add("loops verified", verified_);
  s.add("loops accepted", accepted_);
  for (const auto& [status, n] : by_status_) s.add("loops " + status, n);
  s.add("last loop", last_loop_);
  s.add("candidates waiting", pending_.waiting());
  addCommonLines(s, rejected_input_, last_problem_, guard_, cpu_.seconds());
}

}  // namespace binloop_ros

PLUGINLIB_EXPORT_CLASS(binloop_ros::LoopClosingNodelet, nodelet::Nodelet)
