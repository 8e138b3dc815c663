// binloop/Tracking: see tracking_nodelet.h.
#include "tracking_nodelet.h"

#include <pluginlib/class_list_macros.hpp>

#include "binloop_ros/msg_conversion.h"
#include "binloop_ros/stage_msg_conversion.h"

namespace binloop_ros {

void TrackingNodelet::onInit() {
  ros::NodeHandle& nh = getNodeHandle();
  ros::NodeHandle& pnh = getPrivateNodeHandle();
  try {  // a failure is reported and the nodelet is not loaded; it does not take the manager down
    p_ = TrackingParams::read(pnh);
    stage_ = std::make_unique<binloop::TrackingStage>(p_.config.tracker, p_.camera, p_.keyframe_timeout_s);
    out_ = std::make_unique<TrackingOutputs>(nh, pnh, p_.path_max_poses);
    intake_ = std::make_unique<PairIntake>(topics::StereoTopics(p_.stereo), p_.max_stamp_diff, p_.lockstep,
                                           p_.stamps);
    update_sub_ = guard_.subscribe(nh, "local_map_update", 100, &TrackingNodelet::onUpdate, this);
    // rviz's 2D Pose Estimate (and a robot's own fix): where to relocalise while lost.
    initial_pose_sub_ = guard_.subscribe(nh, "/initialpose", 2, &TrackingNodelet::onInitialPose, this);
    const topics::StereoTopics in(p_.stereo);
    intake_->subscribeInfo(nh, guard_, [this] {
      CpuMeter::Scope cpu(cpu_);
      trackWaiting();
    });
    input_ = std::make_unique<StereoInput>(
        nh, in.left_image, in.right_image, p_.transport, p_.sync, p_.queue_size,
        [this](const ImageConstPtr& l, const ImageConstPtr& r) {
          guard_.run("stereo pair", [&] { onImages(l, r); });
        },
        [this](const std::string& why) { guard_.run("stereo pair", [&] { reject(why); }); });
  } catch (const std::exception& e) {
    NODELET_FATAL("binloop/Tracking: %s", e.what());
    throw;
  }
  diag_ = std::make_unique<StageDiagnostics>(
      nh, pnh, "tracking", [this](diagnostic_updater::DiagnosticStatusWrapper& s) { diagnose(s); });
  services_ = std::make_unique<StageServices>(
      pnh, "tracking", trackingServiceHandlers(*stage_, st_, [this] { startedOver(); }));
  last_pair_wall_ = ros::WallTime::now();  // no pair at all for ~stale_after_s is reported too
  const topics::StereoTopics in(p_.stereo);
  NODELET_INFO("binloop/Tracking: %s sync on %s + %s, map frame '%s'", p_.sync.c_str(), in.left_image.c_str(),
               in.right_image.c_str(), out_->slamFrame().c_str());
}

// Local mapping's map taken by this (restarted) tracking.
void TrackingNodelet::adopted(binloop::TrackingStage::Adopted how) {
  using Adopted = binloop::TrackingStage::Adopted;
  if (how == Adopted::kBehind) return out_->resendKeyframes(*stage_);
  if (how == Adopted::kKept || how == Adopted::kIgnored) return;
  if (how == Adopted::kTakenAfterStartOver) startedOver();
  NODELET_INFO(
      "binloop/Tracking: took local mapping's map (%zu keyframes, %zu points): lost until the next frames "
      "are relocalised in it",
      stage_->tracker()->map().keyframeCount(), stage_->tracker()->map().pointCount());
}

void TrackingNodelet::startedOver() {
  out_->restart();
  intake_->restart();
}

void TrackingNodelet::reject(const std::string& why) {
  ++st_.rejected;
  st_.last_problem = why;
  NODELET_WARN_THROTTLE(1.0, "binloop/Tracking: stereo pair dropped: %s", why.c_str());
}

void TrackingNodelet::problem(const std::string& why) {
  st_.last_problem = why;
  NODELET_WARN_THROTTLE(5.0, "binloop/Tracking: %s", why.c_str());
}

std::string TrackingNodelet::check(const sensor_msgs::Image& left, const sensor_msgs::Image& right) {
  if (std::string bad = intake_->pairProblem(left, right); !bad.empty()) return bad;
  if (!stage_->tracker()) {
    if (!intake_->hasInfo()) return intake_->noInfo();
    try {
      const binloop::StereoCamera cam = intake_->camera();
      const uint64_t adopted_before = stage_->mapsAdopted();
      stage_->setCamera(cam);
      NODELET_INFO("binloop/Tracking: camera from camera_info:\n%s", cam.describe().c_str());
      if (stage_->mapsAdopted() > adopted_before) adopted(binloop::TrackingStage::Adopted::kTaken);
      const std::string distortion = intake_->distortion();
      if (!distortion.empty()) NODELET_WARN("binloop/Tracking: %s", distortion.c_str());
    } catch (const std::exception& e) {
      intake_->forgetInfo();  // wait for a usable pair
      return std::string("camera_info: ") + e.what();
    }
  }
  if (std::string bad = intake_->sizeProblem(left, stage_->tracker()->camera()); !bad.empty()) return bad;
  // Last, as it counts the pairs it takes: the stamp.
  const StampGate::Decision time = intake_->stamp(left.header.stamp);
  if (!time.taken()) return time.reason;
  if (time.verdict == StampGate::Verdict::kRestart) {
    stage_->tracker()->restartClock();
    out_->clockWentBack();
    ++st_.clock_restarts;
  }
  if (time.verdict != StampGate::Verdict::kTake) {
    st_.last_problem = time.reason;
    NODELET_WARN("binloop/Tracking: %s", time.reason.c_str());
  }
  return "";
}

void TrackingNodelet::onImages(const ImageConstPtr& left, const ImageConstPtr& right) {
  CpuMeter::Scope cpu(cpu_);
  out_->resendKeyframes(*stage_);  // to a local mapping that was not listening yet
  last_pair_wall_ = ros::WallTime::now();
  const std::string given_up =
      stage_->inFlight().giveUpIfStale(last_pair_wall_.toSec(), out_->keyframesHeard());
  if (!given_up.empty()) {
    problem(given_up);
    trackWaiting();
  }
  std::string dropped;
  if (!intake_->hold({left, right}, hasCamera(), stage_->inFlight().count(), &dropped))
    return track(left, right);
  if (!dropped.empty()) reject(dropped);
}

void TrackingNodelet::trackWaiting() {
  while (auto pair = intake_->next(hasCamera(), stage_->inFlight().count())) track(pair->first, pair->second);
}

void TrackingNodelet::track(const ImageConstPtr& left, const ImageConstPtr& right) {
  const ros::WallTime t0 = ros::WallTime::now();
  if (std::string bad = check(*left, *right); !bad.empty()) return reject(bad);
  binloop::StereoFrame frame;
  try {
    frame.left = toGray(*left);
    frame.right = toGray(*right);
  } catch (const ConversionError& e) {
    return reject(e.what());
  }
  frame.index = static_cast<int>(st_.frames++);
  frame.stamp_s = left->header.stamp.toSec();
  binloop::Tracker::Output out = stage_->track(frame, ros::WallTime::now().toSec());
  if (out.frame.state == binloop::msg::TrackingState::kLost) ++st_.lost;
  if (!out.frame.problem.empty()) st_.last_problem = out.frame.problem;
  if (out.keyframe) {
    ++st_.keyframes_sent;
    out_->keyframe(*out.keyframe);
  }
  std_msgs::Header header = left->header;
  if (!p_.camera_frame.empty()) header.frame_id = p_.camera_frame;
  const std::string tf_problem = out_->frame(out.frame, header, stage_->corrections());
  if (!tf_problem.empty()) problem(tf_problem);
  out_->debugImage(frame.left, stage_->tracker()->lastFrame(), out.frame, header);
  st_.last_latency_ms = (ros::WallTime::now() - t0).toSec() * 1e3;
}

void TrackingNodelet::onInitialPose(const geometry_msgs::PoseWithCovarianceStampedConstPtr& m) {
  binloop::Tracker* tracker = stage_->tracker();
  if (!tracker) return;
  try {
    const PoseHint hint = out_->frames().hint(*m);
    if (tracker->state() != binloop::msg::TrackingState::kLost) {
      NODELET_INFO("binloop/Tracking: pose hint ignored: tracking is not lost");
      return;
    }
    tracker->hintPose(hint.T_slam_cam, hint.radius_m);
    NODELET_INFO("binloop/Tracking: relocalising within %.1f m of the pose hint", hint.radius_m);
  } catch (const std::exception& e) {
    st_.last_problem = std::string("pose hint refused: ") + e.what();
    NODELET_WARN("binloop/Tracking: %s", st_.last_problem.c_str());
  }
}

void TrackingNodelet::onUpdate(const binloop::LocalMapUpdateConstPtr& m) {
  CpuMeter::Scope cpu(cpu_);
  try {
    binloop::msg::LocalMapUpdate u = fromRos(*m);
    if (u.whole_map)
      return adopted(stage_->adopt(std::make_shared<const binloop::msg::LocalMapUpdate>(std::move(u))));
    stage_->apply(u, ros::WallTime::now().toSec());
    trackWaiting();
  } catch (const std::exception& e) {
    ++st_.rejected;
    st_.last_problem = std::string("local map update dropped: ") + e.what();
    NODELET_WARN_THROTTLE(1.0, "binloop/Tracking: %s", st_.last_problem.c_str());
  }
}

void TrackingNodelet::diagnose(diagnostic_updater::DiagnosticStatusWrapper& s) {
  const double quiet_s = last_pair_wall_.isZero() ? 0 : (ros::WallTime::now() - last_pair_wall_).toSec();
  st_.report(s, *stage_,
             {quiet_s, p_.stale_after_s, intake_->waiting(), intake_->lastStampDiff(), cpu_.seconds()},
             guard_);
}

}  // namespace binloop_ros

PLUGINLIB_EXPORT_CLASS(binloop_ros::TrackingNodelet, nodelet::Nodelet)
