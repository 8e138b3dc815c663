// binloop/LocalMapping: keyframes from tracking in; refined keyframes (to the loop stages) and local-map
// updates (to tracking and loop closing) out; loop corrections in, the corrected map out. Publishes the map
// points (PointCloud2) and the keyframes (PoseArray) for rviz. A short onInit() over binloop::LocalMapper.
#include <geometry_msgs/PoseArray.h>
#include <nodelet/nodelet.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <pluginlib/class_list_macros.hpp>

#include <cstdlib>
#include <memory>

#include "binloop/mapping/local_mapper.h"
#include "binloop/mapping/map_autosave.h"
#include "binloop_ros/callback_guard.h"
#include "binloop_ros/cpu_meter.h"
#include "binloop_ros/node_params.h"
#include "binloop_ros/stage_diagnostics.h"
#include "binloop_ros/stage_msg_conversion.h"
#include "binloop_ros/stage_services.h"

namespace binloop_ros {

class LocalMappingNodelet : public nodelet::Nodelet {
 public:
  void onInit() override;

 private:
  void onKeyframe(const binloop::KeyFrameConstPtr& m);
  void onCorrection(const binloop::CorrectionConstPtr& m);
  void mergeGlobalBa();
  void resendMap(const ros::SingleSubscriberPublisher& to);
  void resendWholeMap(const ros::SingleSubscriberPublisher& to);
  StageServiceHandlers serviceHandlers();
  void publishMap(const ros::Time& stamp);
  void problem(const std::string& what);
  void setUpAutosave(ros::NodeHandle& pnh);
  void autosave(bool after_keyframe);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& s);

  binloop::LocalMapperParams params_;
  std::unique_ptr<binloop::LocalMapper> mapper_;
  std::unique_ptr<StageServices> services_;
  std::unique_ptr<binloop::MapAutosave> autosave_;
  CallbackGuard guard_{"LocalMapping"};
  std::string counts() const;
  std::string slam_frame_;
  int cloud_every_ = 5;
  ros::Subscriber keyframe_sub_, correction_sub_;
  ros::WallTimer merge_timer_;
  ros::Publisher refined_pub_, update_pub_, cloud_pub_, keyframes_pub_;
  std::unique_ptr<StageDiagnostics> diag_;
  CpuMeter cpu_;
  uint64_t keyframes_ = 0, corrections_ = 0, rejected_ = 0, resends_ = 0;
  size_t resumed_keyframes_ = 0;  // from the autosave, at start
  double last_ms_ = 0, last_ba_ms_ = 0;
  std::string last_problem_;
};

void LocalMappingNodelet::onInit() {
  ros::NodeHandle& nh = getNodeHandle();
  ros::NodeHandle& pnh = getPrivateNodeHandle();
  try {
    requireKnownParams(
        pnh, {"config", "slam_frame", "cloud_every", "autosave_every", "autosave_path", "autosave_session"});
    params_ = slamConfigFrom(pnh).mapper;
    params_.global_ba_in_background = true;  // mapping goes on while it runs (with global_ba_after_loop)
    setUpAutosave(pnh);
  } catch (const std::exception& e) {
    NODELET_FATAL("binloop/LocalMapping: %s", e.what());
    throw;
  }
  slam_frame_ = stringParam(pnh, "slam_frame", "slam");  // tracking publishes map -> slam
  cloud_every_ = std::max(1, static_cast<int>(numberParam(pnh, "cloud_every", 5)));
  // A loop stage that subscribes after keyframes were made (a restarted process of the split graph) gets the
  // whole map from here, to it alone; a deep queue, since all of them go at once.
  refined_pub_ = nh.advertise<binloop::KeyFrame>(
      "refined_keyframe", 10000,
      guard_.wrap("resending the map", [this](const ros::SingleSubscriberPublisher& to) { resendMap(to); }));
  // A tracking that subscribes after keyframes were made (restarted) gets the whole map, to it alone.
  update_pub_ = nh.advertise<binloop::LocalMapUpdate>(
      "local_map_update", 100,
      guard_.wrap("resending the map",
                  [this](const ros::SingleSubscriberPublisher& to) { resendWholeMap(to); }));
  cloud_pub_ = nh.advertise<sensor_msgs::PointCloud2>("map_points", 1, true);
  keyframes_pub_ = nh.advertise<geometry_msgs::PoseArray>("keyframes", 1, true);
  // Deep queues: a keyframe or a correction dropped here would be lost for good.
  keyframe_sub_ = guard_.subscribe(nh, "keyframe", 1000, &LocalMappingNodelet::onKeyframe, this);
  correction_sub_ = guard_.subscribe(nh, "correction", 100, &LocalMappingNodelet::onCorrection, this);
  // A background global BA is merged when it is done, whether or not keyframes come (same queue as them).
  // Wall clock: under simulated time a ROS timer stops with /clock when the bag ends, and the last global BA
  // would never be merged.
  merge_timer_ = nh.createWallTimer(
      ros::WallDuration(0.1),
      guard_.wrap("global BA merge", [this](const ros::WallTimerEvent&) { mergeGlobalBa(); }));
  diag_ = std::make_unique<StageDiagnostics>(
      nh, pnh, "local mapping", [this](diagnostic_updater::DiagnosticStatusWrapper& s) { diagnose(s); });
  services_ = std::make_unique<StageServices>(pnh, "local_mapping", serviceHandlers());
}

// A respawned process resumes its graph's autosave (mapping/map_autosave.h), before anyone subscribes: the
// map then goes to every stage that connects, and tracking sends the keyframes made after the save again.
void LocalMappingNodelet::setUpAutosave(ros::NodeHandle& pnh) {
  const char* home = std::getenv("ROS_HOME");
  const std::string ros_home =
      home ? home : std::string(std::getenv("HOME") ? std::getenv("HOME") : ".") + "/.ros";
  const int every = static_cast<int>(numberParam(pnh, "autosave_every", 0));
  autosave_ = std::make_unique<binloop::MapAutosave>(
      stringParam(pnh, "autosave_path", ros_home + "/binloop/local_mapping.autosave"), every,
      stringParam(pnh, "autosave_session", ""));
  std::string note;
  mapper_ = autosave_->resume(params_, &note);
  if (mapper_) resumed_keyframes_ = mapper_->keyframeCount();
  if (!mapper_) mapper_ = std::make_unique<binloop::LocalMapper>(params_);
  if (autosave_->on())
    NODELET_INFO("binloop/LocalMapping: autosave every %d keyframes: %s", every, note.c_str());
}

// Saves the map for a respawn (every N keyframes, or now: after a loop, a global BA, a load or a reset); a
// failure is said and mapping goes on.
void LocalMappingNodelet::autosave(bool after_keyframe) {
  try {
    if (after_keyframe)
      autosave_->afterKeyframe(*mapper_);
    else
      autosave_->save(*mapper_);
  } catch (const std::exception& e) {
    problem(std::string("autosave failed: ") + e.what());
  }
}

// The stage's part in the graph-wide map services (stage_services.h).
StageServiceHandlers LocalMappingNodelet::serviceHandlers() {
  StageServiceHandlers h;
  h.save = [this](const std::string& path, uint64_t map_id) {
    binloop::saveStateFile(*mapper_, path, "local_mapping", map_id);
    return counts();
  };
  h.prepare = [this](const std::string& path) {
    auto fresh = std::make_shared<std::unique_ptr<binloop::LocalMapper>>(
        loadStage(std::make_unique<binloop::LocalMapper>(params_), path, "local_mapping"));
    return PreparedLoad{[this, fresh] {
      (*fresh)->continueIdsInNewSession(mapper_->pointIdsIssued());
      mapper_ = std::move(*fresh);
      publishMap(ros::Time::now());
      autosave(false);
      return counts();
    }};
  };
  h.reset = [this] {
    // Ids go on in a new session: an update of the old map may still be on its way to the other stages.
    auto fresh = std::make_unique<binloop::LocalMapper>(params_);
    fresh->continueIdsInNewSession(mapper_->pointIdsIssued());
    mapper_ = std::move(fresh);
    publishMap(ros::Time::now());
    autosave(false);
  };
  h.statistics = [this] {
    return StageStatistics{{"keyframes", std::to_string(mapper_->keyframeCount())},
                           {"map_points", std::to_string(mapper_->pointCount())},
                           {"corrections", std::to_string(mapper_->correctionsApplied())},
                           {"global_ba_merged", std::to_string(mapper_->globalBaStats().merged)},
                           {"resumed_keyframes", std::to_string(resumed_keyframes_)}};
  };
  return h;
}

// A tracking that subscribes after keyframes were made (restarted) gets the whole map, to it alone.
void LocalMappingNodelet::resendWholeMap(const ros::SingleSubscriberPublisher& to) {
  if (mapper_->keyframeCount() == 0) return;
  std_msgs::Header header;
  header.stamp = ros::Time::now();
  header.frame_id = slam_frame_;
  to.publish(toRos(*mapper_->wholeMap(), header));
}

std::string LocalMappingNodelet::counts() const {
  return std::to_string(mapper_->keyframeCount()) + " keyframes, " + std::to_string(mapper_->pointCount()) +
         " map points";
}

void LocalMappingNodelet::problem(const std::string& what) {
  ++rejected_;
  last_problem_ = what;
  NODELET_WARN_THROTTLE(1.0, "binloop/LocalMapping: %s", what.c_str());
}

void LocalMappingNodelet::mergeGlobalBa() {
  CpuMeter::Scope cpu(cpu_);
  binloop::msg::LocalMapUpdatePtr u = mapper_->mergeGlobalBa();
  if (!u) return;
  std_msgs::Header header;
  header.stamp = ros::Time::now();
  header.frame_id = slam_frame_;
  update_pub_.publish(boost::make_shared<binloop::LocalMapUpdate>(toRos(*u, header)));
  publishMap(header.stamp);
  autosave(false);
  NODELET_INFO("binloop/LocalMapping: global BA merged (%.0f ms over %d keyframes, %d added meanwhile)",
               mapper_->globalBaStats().last.ms(), mapper_->globalBaStats().last_keyframes,
               mapper_->globalBaStats().last_added_meanwhile);
}

void LocalMappingNodelet::onKeyframe(const binloop::KeyFrameConstPtr& m) {
  mergeGlobalBa();  // one that finished goes out before the keyframe's update
  CpuMeter::Scope cpu(cpu_);
  binloop::LocalMapper::Output out;
  try {
    out = mapper_->process(fromRos(*m));
  } catch (const std::exception& e) {  // ConversionError, std::invalid_argument: the message is dropped
    return problem(std::string("keyframe dropped: ") + e.what());
  }
  ++keyframes_;
  last_ms_ = out.update->total_ms;
  last_ba_ms_ = out.update->ba_ms;
  std_msgs::Header header = m->header;
  header.frame_id = slam_frame_;
  // The refined keyframe first: loop closing must know it before the update that names it.
  refined_pub_.publish(boost::make_shared<binloop::KeyFrame>(toRos(*out.refined, slam_frame_)));
  update_pub_.publish(boost::make_shared<binloop::LocalMapUpdate>(toRos(*out.update, header)));
  if (keyframes_ % cloud_every_ == 0) publishMap(m->header.stamp);
  autosave(true);
}

void LocalMappingNodelet::resendMap(const ros::SingleSubscriberPublisher& to) {
  const std::vector<binloop::msg::KeyFramePtr> kfs = mapper_->keyframeMessages();
  if (kfs.empty()) return;
  for (const auto& kf : kfs) to.publish(toRos(*kf, slam_frame_));
  ++resends_;
  NODELET_INFO(
      "binloop/LocalMapping: %s subscribed after %zu keyframes: sent them again (%lu corrections applied)",
      to.getSubscriberName().c_str(), kfs.size(), static_cast<unsigned long>(mapper_->correctionsApplied()));
}

void LocalMappingNodelet::onCorrection(const binloop::CorrectionConstPtr& m) {
  CpuMeter::Scope cpu(cpu_);
  binloop::msg::LocalMapUpdatePtr u;
  try {
    u = mapper_->apply(fromRos(*m));
  } catch (const std::exception& e) {
    return problem(std::string("correction dropped: ") + e.what());
  }
  if (!u) return;  // sent again, but this one had arrived: applied once
  ++corrections_;
  // Saved before tracking hears of it: a respawn from an autosave without it would get tracking's later
  // keyframes in the corrected frame. Killed before the save, nobody has applied it and loop closing sends
  // it again (loop/correction_outbox.h).
  try {
    autosave_->saveBeforeGoingOn(*mapper_);
  } catch (const std::exception& e) {
    problem(std::string("autosave failed: ") + e.what());
  }
  std_msgs::Header header = m->header;
  header.frame_id = slam_frame_;
  update_pub_.publish(boost::make_shared<binloop::LocalMapUpdate>(toRos(*u, header)));
  publishMap(m->header.stamp);
}

void LocalMappingNodelet::publishMap(const ros::Time& stamp) {
  if (cloud_pub_.getNumSubscribers() > 0 || cloud_pub_.isLatched()) {
    const auto pts = mapper_->pointPositions();
    sensor_msgs::PointCloud2 cloud;
    cloud.header.stamp = stamp;
    cloud.header.frame_id = slam_frame_;
    sensor_msgs::PointCloud2Modifier mod(cloud);
    mod.setPointCloud2FieldsByString(1, "xyz");
    mod.resize(pts.size());
    sensor_msgs::PointCloud2Iterator<float> x(cloud, "x"), y(cloud, "y"), z(cloud, "z");
    for (const auto& p : pts) {
      *x = static_cast<float>(p.x());
      *y = static_cast<float>(p.y());
      *z = static_cast<float>(p.z());
      ++x, ++y, ++z;
    }
    cloud_pub_.publish(cloud);
  }
  geometry_msgs::PoseArray kfs;
  kfs.header.stamp = stamp;
  kfs.header.frame_id = slam_frame_;
  for (const auto& k : mapper_->keyframes()) kfs.poses.push_back(toPoseMsg(k.T_w_c));
  keyframes_pub_.publish(kfs);
}

void LocalMappingNodelet::diagnose(diagnostic_updater::DiagnosticStatusWrapper& s) {
  s.summary(rejected_ ? diagnostic_msgs::DiagnosticStatus::WARN : diagnostic_msgs::DiagnosticStatus::OK,
            rejected_ ? "mapping; some input dropped" : "mapping");
  s.add("keyframes processed", keyframes_);
  s.add("keyframes in map", mapper_->keyframeCount());
  s.add("map points", mapper_->pointCount());
  s.add("corrections applied", corrections_);
  s.add("map sent again to a new subscriber", resends_);
  s.add("global BAs failed", mapper_ ? mapper_->globalBaStats().failed : 0);
  s.add("last global BA failure", mapper_ ? mapper_->globalBaStats().last_failure : std::string());
  s.add("last keyframe ms", last_ms_);
  s.add("last local BA ms", last_ba_ms_);
  s.add("autosaves", autosave_ ? autosave_->saves() : 0);
  s.add("last autosave ms", autosave_ ? autosave_->lastMs() : 0.0);
  s.add("last autosave MB", autosave_ ? autosave_->lastBytes() / 1e6 : 0.0);
  addCommonLines(s, rejected_, last_problem_, guard_, cpu_.seconds());
}

}  // namespace binloop_ros

PLUGINLIB_EXPORT_CLASS(binloop_ros::LocalMappingNodelet, nodelet::Nodelet)
