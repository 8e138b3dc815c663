// binloop/LoopDetector: refined keyframes in, LoopCandidates out (one per keyframe; shadow models on their
// own topics). dynamic_reconfigure switches the model (`method`) and sets the detection rules and model
// thresholds; the new index is built from the stored keyframes at the next keyframe, without stopping. A
// short onInit() over binloop::LoopDetector.
#include <binloop/LoopDetectorConfig.h>
#include <dynamic_reconfigure/server.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include <map>
#include <memory>
#include <sstream>

#include "binloop/loop/loop_detector.h"
#include "binloop/pipeline/model_files.h"
#include "binloop/util/package_paths.h"
#include "binloop_ros/callback_guard.h"
#include "binloop_ros/candidate_markers.h"
#include "binloop_ros/cpu_meter.h"
#include "binloop_ros/node_params.h"
#include "binloop_ros/stage_diagnostics.h"
#include "binloop_ros/stage_msg_conversion.h"
#include "binloop_ros/stage_services.h"

namespace binloop_ros {

class LoopDetectorNodelet : public nodelet::Nodelet {
 public:
  void onInit() override;

 private:
  void onKeyframe(const binloop::KeyFrameConstPtr& m);
  void onReconfigure(binloop::LoopDetectorConfig& c, uint32_t level);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& s);
  ros::Publisher& shadowPublisher(const std::string& model);
  /// A detector with the rules, models and shadow models of the last reconfiguration.
  std::unique_ptr<binloop::LoopDetector> makeDetector() const;
  void defaultRulesFromConfig(ros::NodeHandle& pnh) const;
  StageServiceHandlers serviceHandlers();
  std::string counts() const;

  binloop::LoopDetectorParams params_;
  binloop::LoopDetector::ModelFactory make_;
  std::vector<std::string> shadow_;
  std::unique_ptr<StageServices> services_;
  CallbackGuard guard_{"LoopDetector"};

  binloop::SlamConfig config_;
  std::string vocab_dir_;
  bool force_ = false;
  std::unique_ptr<binloop::LoopDetector> detector_;
  std::unique_ptr<dynamic_reconfigure::Server<binloop::LoopDetectorConfig>> reconfigure_;
  ros::Subscriber keyframe_sub_;
  ros::Publisher candidates_pub_, markers_pub_;
  CandidateMarkers markers_;  // the live loop view (rviz)
  std::map<std::string, ros::Publisher> shadow_pubs_;
  std::unique_ptr<StageDiagnostics> diag_;
  CpuMeter cpu_;
  uint64_t queries_ = 0, accepted_ = 0, rejected_ = 0;
  std::string last_problem_, last_status_;
  double last_ms_ = 0, last_switch_ms_ = 0;
};

void LoopDetectorNodelet::onInit() {
  ros::NodeHandle& nh = getNodeHandle();
  ros::NodeHandle& pnh = getPrivateNodeHandle();
  try {
    requireKnownParams(pnh, {"config", "vocab_dir", "force_extractor", "method", "consistency",
                             "max_reference", "ignore_recent", "hbow_min_bar", "fabmap_l2_offset",
                             "vladpq_shared_slack", "vlad_reference_rank", "shadow"});
    config_ = slamConfigFrom(pnh);
  } catch (const std::exception& e) {
    NODELET_FATAL("binloop/LoopDetector: %s", e.what());
    throw;
  }
  vocab_dir_ = binloop::modelDirFor(stringParam(pnh, "vocab_dir", binloop::kAutoVocab),
                                    config_.tracker.orb.pattern == binloop::BriefPatternKind::kOrbLearned);
  force_ = boolParam(pnh, "force_extractor", false);
  defaultRulesFromConfig(pnh);
  candidates_pub_ = nh.advertise<binloop::LoopCandidates>("loop_candidates", 100);
  markers_pub_ = nh.advertise<visualization_msgs::MarkerArray>("loop_candidate_markers", 10);
  diag_ = std::make_unique<StageDiagnostics>(
      nh, pnh, "loop detector", [this](diagnostic_updater::DiagnosticStatusWrapper& s) { diagnose(s); });
  reconfigure_ = std::make_unique<dynamic_reconfigure::Server<binloop::LoopDetectorConfig>>(pnh);
  reconfigure_->setCallback([this](binloop::LoopDetectorConfig& c, uint32_t level) {
    guard_.run("dynamic_reconfigure", [&] { onReconfigure(c, level); });
  });
  keyframe_sub_ = guard_.subscribe(nh, "refined_keyframe", 1000, &LoopDetectorNodelet::onKeyframe, this);
  services_ = std::make_unique<StageServices>(pnh, "loop_detector", serviceHandlers());
}

// The file's loop_detection section gives the starting rules unless the parameters say otherwise
// (dynamic_reconfigure starts from the parameters).
void LoopDetectorNodelet::defaultRulesFromConfig(ros::NodeHandle& pnh) const {
  if (!pnh.hasParam("consistency")) pnh.setParam("consistency", config_.detector.consistency);
  if (!pnh.hasParam("max_reference")) pnh.setParam("max_reference", config_.detector.max_reference);
  if (!pnh.hasParam("ignore_recent")) pnh.setParam("ignore_recent", config_.detector.ignore_recent);
  if (!pnh.hasParam("hbow_min_bar")) pnh.setParam("hbow_min_bar", config_.models.hbow_min_bar);
  if (!pnh.hasParam("fabmap_l2_offset")) pnh.setParam("fabmap_l2_offset", config_.models.fabmap_l2_offset);
  if (!pnh.hasParam("vladpq_shared_slack"))
    pnh.setParam("vladpq_shared_slack", config_.models.vladpq_shared_slack);
  if (!pnh.hasParam("vlad_reference_rank"))
    pnh.setParam("vlad_reference_rank", config_.models.vlad_reference_rank);
}

// The stage's part in the graph-wide map services (stage_services.h).
StageServiceHandlers LoopDetectorNodelet::serviceHandlers() {
  StageServiceHandlers h;
  auto need = [this] {
    if (!detector_) throw std::runtime_error("no usable loop model: " + last_problem_);
  };
  h.save = [this, need](const std::string& path, uint64_t map_id) {
    need();
    binloop::saveStateFile(*detector_, path, "loop_detector", map_id);
    return counts();
  };
  h.prepare = [this, need](const std::string& path) {
    need();
    auto fresh = std::make_shared<decltype(detector_)>(loadStage(makeDetector(), path, "loop_detector"));
    return PreparedLoad{[this, fresh] {
      detector_ = std::move(*fresh);
      return counts() + " (index rebuilt from the map's keyframes)";
    }};
  };
  h.reset = [this, need] {
    need();
    detector_ = makeDetector();
  };
  h.statistics = [this] {
    StageStatistics s{{"queries", std::to_string(queries_)},
                      {"candidates_accepted", std::to_string(accepted_)}};
    if (detector_) {
      s.emplace_back("model", detector_->activeModel());
      s.emplace_back("keyframes", std::to_string(detector_->keyframeCount()));
      s.emplace_back("index_keyframes", std::to_string(detector_->indexSize()));
      s.emplace_back("index_bytes", std::to_string(detector_->indexBytes()));
    }
    return s;
  };
  return h;
}

std::unique_ptr<binloop::LoopDetector> LoopDetectorNodelet::makeDetector() const {
  auto d = std::make_unique<binloop::LoopDetector>(params_, make_);
  d->setShadowModels(shadow_);
  d->setModelIdentity(binloop::modelFileIdentities(vocab_dir_));
  return d;
}

std::string LoopDetectorNodelet::counts() const {
  return std::to_string(detector_->keyframeCount()) + " keyframes, " + detector_->activeModel() +
         " index of " + std::to_string(detector_->indexSize()) + " keyframes (" +
         std::to_string(detector_->indexBytes() >> 10) + " kB)";
}

void LoopDetectorNodelet::onReconfigure(binloop::LoopDetectorConfig& c, uint32_t) {
  CpuMeter::Scope cpu(cpu_);
  binloop::LoopDetectorParams p = config_.detector;
  p.model = c.method;
  p.consistency = c.consistency;
  p.max_reference = c.max_reference;
  p.ignore_recent = c.ignore_recent;
  binloop::RecognizerOptions options = config_.models;
  options.hbow_min_bar = c.hbow_min_bar;
  options.fabmap_l2_offset = c.fabmap_l2_offset;
  options.vladpq_shared_slack = c.vladpq_shared_slack;
  options.vlad_reference_rank = c.vlad_reference_rank;
  auto make = binloop::modelFileFactory(vocab_dir_, config_.tracker.orb, force_, options);
  try {
    std::vector<std::string> skipped;
    const std::vector<std::string> shadow =
        binloop::shadowModelNames(c.shadow, p.model, vocab_dir_, &skipped);
    for (const std::string& n : skipped)
      NODELET_WARN("binloop/LoopDetector: shadow model %s skipped: no %s.bin in %s", n.c_str(), n.c_str(),
                   vocab_dir_.c_str());
    if (!detector_) {
      detector_ = std::make_unique<binloop::LoopDetector>(p, make);
      detector_->setModelIdentity(binloop::modelFileIdentities(vocab_dir_));
    } else {
      detector_->reconfigure(p, make);
    }
    detector_->setShadowModels(shadow);
    params_ = p;
    make_ = make;
    shadow_ = shadow;
    last_problem_.clear();
    NODELET_INFO("binloop/LoopDetector: %s from the next keyframe (consistency %d, %zu shadow models)",
                 p.model.c_str(), p.consistency, shadow.size());
  } catch (const std::exception& e) {  // a missing or mismatched model file: the running model stays
    last_problem_ = std::string("cannot use ") + p.model + ": " + e.what();
    NODELET_ERROR("binloop/LoopDetector: %s", last_problem_.c_str());
    if (detector_) c.method = detector_->activeModel();
  }
}

ros::Publisher& LoopDetectorNodelet::shadowPublisher(const std::string& model) {
  auto it = shadow_pubs_.find(model);
  if (it == shadow_pubs_.end())
    it = shadow_pubs_
             .emplace(model, getNodeHandle().advertise<binloop::LoopCandidates>(
                                 "shadow/" + model + "/loop_candidates", 100))
             .first;
  return it->second;
}

void LoopDetectorNodelet::onKeyframe(const binloop::KeyFrameConstPtr& m) {
  CpuMeter::Scope cpu(cpu_);
  if (!detector_) return;  // no usable model: said at start-up and in the diagnostics
  binloop::LoopDetector::Output out;
  try {
    out = detector_->process(fromRos(*m));
  } catch (const std::exception& e) {
    ++rejected_;
    last_problem_ = std::string("keyframe dropped: ") + e.what();
    NODELET_WARN_THROTTLE(1.0, "binloop/LoopDetector: %s", last_problem_.c_str());
    return;
  }
  if (out.switch_ms > 0) last_switch_ms_ = out.switch_ms;
  std_msgs::Header header = m->header;
  if (out.active) {
    ++queries_;
    if (out.active->accepted != binloop::kNoId) ++accepted_;
    last_status_ = out.active->status;
    last_ms_ = out.active->total_ms;
    auto msg = boost::make_shared<binloop::LoopCandidates>(toRos(*out.active, header));
    candidates_pub_.publish(msg);
    const auto& p = m->state.pose.position;
    markers_.keyframe(m->id, Eigen::Vector3d(p.x, p.y, p.z), m->header.frame_id);
    if (markers_pub_.getNumSubscribers() > 0) markers_pub_.publish(markers_.markers(*msg));
  }
  for (const auto& s : out.shadow)
    shadowPublisher(s->model).publish(boost::make_shared<binloop::LoopCandidates>(toRos(*s, header)));
}

void LoopDetectorNodelet::diagnose(diagnostic_updater::DiagnosticStatusWrapper& s) {
  if (!detector_)
    s.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "no usable model: " + last_problem_);
  else if (!last_problem_.empty())
    s.summary(diagnostic_msgs::DiagnosticStatus::WARN, last_problem_);
  else
    s.summary(diagnostic_msgs::DiagnosticStatus::OK, "detecting with " + detector_->activeModel());
  s.add("active model", detector_ ? detector_->activeModel() : std::string("none"));
  s.add("index size (keyframes)", detector_ ? detector_->keyframeCount() : 0);
  s.add("queries", queries_);
  s.add("candidates accepted", accepted_);
  s.add("last status", last_status_);
  s.add("last detection ms", last_ms_);
  s.add("last switch rebuild ms", last_switch_ms_);
  addCommonLines(s, rejected_, last_problem_, guard_, cpu_.seconds());
}

}  // namespace binloop_ros

PLUGINLIB_EXPORT_CLASS(binloop_ros::LoopDetectorNodelet, nodelet::Nodelet)
