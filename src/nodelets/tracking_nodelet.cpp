// binloop/Tracking: stereo images in, the camera's pose out (pose, odometry, path, tf), keyframes to local
// mapping; local mapping's updates back in. A short onInit() over binloop::Tracker; every message check is
// here, so a bad message is reported (log + diagnostics) and dropped, and the nodelet goes on.
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <nav_msgs/Path.h>
#include <nodelet/nodelet.h>
#include <opencv2/imgproc.hpp>
#include <pluginlib/class_list_macros.hpp>

#include <deque>
#include <memory>
#include <optional>
#include <utility>

#include "binloop/pipeline/model_files.h"
#include "binloop/tracking/keyframes_in_flight.h"
#include "binloop/tracking/tracker.h"
#include "binloop/util/package_paths.h"
#include "binloop_ros/callback_guard.h"
#include "binloop_ros/frame_publisher.h"
#include "binloop_ros/stereo_input.h"
#include "binloop_ros/cpu_meter.h"
#include "binloop_ros/stage_diagnostics.h"
#include "binloop_ros/node_params.h"
#include "binloop_ros/stage_msg_conversion.h"
#include "binloop_ros/stage_services.h"
#include "binloop_ros/stamp_gate.h"
#include "binloop_ros/topics.h"

namespace binloop_ros {

using sensor_msgs::Image;

class TrackingNodelet : public nodelet::Nodelet {
 public:
  void onInit() override;

 private:
  void onPair(const sensor_msgs::ImageConstPtr& left, const sensor_msgs::ImageConstPtr& right) {
    guard_.run("stereo pair", [&] { onImages(left, right); });
  }
  void onImages(const sensor_msgs::ImageConstPtr& left, const sensor_msgs::ImageConstPtr& right);
  void track(const sensor_msgs::ImageConstPtr& left, const sensor_msgs::ImageConstPtr& right);
  void trackWaiting();
  void onUpdate(const binloop::LocalMapUpdateConstPtr& u);
  void onInitialPose(const geometry_msgs::PoseWithCovarianceStampedConstPtr& m);
  void onInfo(const sensor_msgs::CameraInfoConstPtr& info, bool right);
  std::string check(const Image& left, const Image& right);
  void publishPose(const binloop::msg::TrackedFrame& f, const std_msgs::Header& header);
  void reject(const std::string& why);
  void publishDebugImage(const cv::Mat& gray, const binloop::msg::TrackedFrame& f, const std_msgs::Header& header);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& s);
  void startOver(std::unique_ptr<binloop::Tracker> t);
  void adopt(binloop::msg::LocalMapUpdatePtr whole);
  std::unique_ptr<StageServices> services_;
  CallbackGuard guard_{"Tracking"};
  std::unique_ptr<StampGate> stamps_;
  double stale_after_s_ = 2;
  size_t path_max_poses_ = 1000;
  ros::WallTime last_pair_wall_;
  uint64_t clock_restarts_ = 0;
  uint64_t maps_adopted_ = 0;
  binloop::msg::LocalMapUpdatePtr adopt_;  // local mapping's map, until the camera is known

  binloop::SlamConfig config_;
  std::unique_ptr<binloop::Tracker> tracker_;
  std::optional<binloop::StereoCamera> fixed_camera_;  // from parameters, instead of camera_info
  sensor_msgs::CameraInfoConstPtr left_info_, right_info_;
  std::string camera_frame_;
  std::unique_ptr<FramePublisher> frames_out_;  // tf, odom
  double max_stamp_diff_ = 0;
  // ~lockstep: a pair waits until local mapping has answered every keyframe sent, as `run --lockstep` does
  // (for comparing the two paths; live, tracking never waits). Pairs also wait for the first camera_info.
  bool lockstep_ = false;
  std::deque<std::pair<sensor_msgs::ImageConstPtr, sensor_msgs::ImageConstPtr>> waiting_;
  topics::StereoTopics in_{topics::kStereoNamespace};  // ~stereo: the input topics' namespace
  std::unique_ptr<StereoInput> input_;
  ros::Subscriber left_info_sub_, right_info_sub_, update_sub_, initial_pose_sub_;
  ros::Publisher keyframe_pub_, frame_pub_, pose_pub_, path_pub_, debug_pub_;
  std::unique_ptr<StageDiagnostics> diag_;
  CpuMeter cpu_;
  nav_msgs::Path path_;
  uint64_t frames_ = 0, rejected_ = 0, keyframes_sent_ = 0, lost_ = 0;
  binloop::KeyframesInFlight in_flight_;  // keyframes sent to mapping and not yet answered (~keyframe_timeout_s)
  size_t max_waiting_ = 100;            // lock-step pairs held for mapping at most (the oldest are dropped)
  uint64_t corrections_ = 0;    // corrected maps applied: the slam-frame pose may jump then, odom must not
  uint64_t corrections_at_last_ = 0;
  std::string last_problem_;
  double last_stamp_diff_ = 0, last_latency_ms_ = 0;
};

void TrackingNodelet::onInit() {
  ros::NodeHandle& nh = getNodeHandle();
  ros::NodeHandle& pnh = getPrivateNodeHandle();
  try {
    std::vector<std::string> known = {"config", "reloc_vocab", "force_extractor", "sync", "queue_size", "max_stamp_diff",
                                      "camera_frame", "camera", "seed", "lockstep", "max_time_jump", "transport", "stereo",
                                      "time_jump_confirm_pairs", "stale_after_s", "path_max_poses", "keyframe_timeout_s",
                                      "localize_only"};
    known.insert(known.end(), FramePublisher::parameterNames().begin(), FramePublisher::parameterNames().end());
    requireKnownParams(pnh, known);
    in_flight_ = binloop::KeyframesInFlight(numberParam(pnh, "keyframe_timeout_s", 5));
    stamps_ = std::make_unique<StampGate>(StampGateParams{numberParam(pnh, "max_time_jump", 5),
                                                          static_cast<int>(numberParam(pnh, "time_jump_confirm_pairs", 3))});
    stale_after_s_ = numberParam(pnh, "stale_after_s", 2);
    path_max_poses_ = static_cast<size_t>(std::max(1.0, numberParam(pnh, "path_max_poses", 1000)));
    config_ = slamConfigFrom(pnh);
    config_.tracker.seed = static_cast<uint64_t>(numberParam(pnh, "seed", 1));
    config_.tracker.localize_only = boolParam(pnh, "localize_only", config_.tracker.localize_only);
    // "" or "none": relocalisation tries only the most recent keyframes.
    const std::string reloc = stringParam(pnh, "reloc_vocab", binloop::packagePath(binloop::kRelocVocab));
    if (!reloc.empty() && reloc != "none") {
      config_.tracker.vocabulary =
          binloop::loadRelocalisationVocabulary(reloc, config_.tracker.orb, boolParam(pnh, "force_extractor", false));
      config_.tracker.vocabulary_identity = binloop::modelFileIdentity(reloc);
    }
    if (pnh.hasParam("camera")) {  // calibration from YAML (rosparam) instead of camera_info
      binloop::StereoCamera cam;
      cam.fx = numberParam(pnh, "camera/fx", 0);
      cam.fy = numberParam(pnh, "camera/fy", 0);
      cam.cx = numberParam(pnh, "camera/cx", 0);
      cam.cy = numberParam(pnh, "camera/cy", 0);
      cam.baseline_m = numberParam(pnh, "camera/baseline", 0);
      cam.width = static_cast<int>(numberParam(pnh, "camera/width", 0));
      cam.height = static_cast<int>(numberParam(pnh, "camera/height", 0));
      fixed_camera_ = cam;
      tracker_ = std::make_unique<binloop::Tracker>(cam, config_.tracker);  // throws for a bad camera
    }
  } catch (const std::exception& e) {
    NODELET_FATAL("binloop/Tracking: %s", e.what());
    throw;  // the manager reports the nodelet as failed to load; it does not take the manager down
  }
  camera_frame_ = stringParam(pnh, "camera_frame", "");  // "": the left image's frame_id
  try {
    frames_out_ = std::make_unique<FramePublisher>(nh, pnh);
  } catch (const std::exception& e) {
    NODELET_FATAL("binloop/Tracking: %s", e.what());
    throw;
  }
  max_stamp_diff_ = numberParam(pnh, "max_stamp_diff", 0.002);
  lockstep_ = boolParam(pnh, "lockstep", false);
  const int queue = static_cast<int>(numberParam(pnh, "queue_size", 5));
  const std::string sync = stringParam(pnh, "sync", "exact");
  in_ = topics::StereoTopics(stringParam(pnh, "stereo", topics::kStereoNamespace));

  keyframe_pub_ = nh.advertise<binloop::KeyFrame>("keyframe", 10);
  frame_pub_ = nh.advertise<binloop::TrackedFrame>("tracked_frame", 100);
  pose_pub_ = nh.advertise<geometry_msgs::PoseStamped>("pose", 10);
  path_pub_ = nh.advertise<nav_msgs::Path>("live_path", 1, true);
  debug_pub_ = nh.advertise<sensor_msgs::Image>("debug_image", 1);
  update_sub_ = guard_.subscribe(nh, "local_map_update", 100, &TrackingNodelet::onUpdate, this);
  // rviz's 2D Pose Estimate (and a robot's own fix): where to relocalise while lost.
  initial_pose_sub_ = guard_.subscribe(nh, "/initialpose", 2, &TrackingNodelet::onInitialPose, this);
  left_info_sub_ = nh.subscribe<sensor_msgs::CameraInfo>(
      in_.left_info, 2, guard_.wrap("left camera_info", [this](const sensor_msgs::CameraInfoConstPtr& m) { onInfo(m, false); }));
  right_info_sub_ = nh.subscribe<sensor_msgs::CameraInfo>(
      in_.right_info, 2, guard_.wrap("right camera_info", [this](const sensor_msgs::CameraInfoConstPtr& m) { onInfo(m, true); }));
  try {
    input_ = std::make_unique<StereoInput>(
        nh, in_.left_image, in_.right_image, stringParam(pnh, "transport", "raw"), sync, queue,
        [this](const sensor_msgs::ImageConstPtr& l, const sensor_msgs::ImageConstPtr& r) { onPair(l, r); },
        [this](const std::string& why) { guard_.run("stereo pair", [&] { reject(why); }); });
  } catch (const std::invalid_argument& e) {
    NODELET_FATAL("binloop/Tracking: %s", e.what());
    throw;
  }
  diag_ = std::make_unique<StageDiagnostics>(
      nh, pnh, "tracking", [this](diagnostic_updater::DiagnosticStatusWrapper& s) { diagnose(s); });
  StageServiceHandlers h;
  h.save = [this](const std::string& path, uint64_t map_id) {
    if (!tracker_) throw std::runtime_error("tracking has no camera yet, so no map");
    binloop::saveStateFile(*tracker_, path, "tracking", map_id);
    return std::to_string(tracker_->map().keyframeCount()) + " keyframes, " +
           std::to_string(tracker_->map().pointCount()) + " map points in its replica";
  };
  h.prepare = [this](const std::string& path) {
    // Without a camera yet, the map's own: the first camera_info must then agree with it (image sizes are checked).
    const binloop::StereoCamera cam = tracker_ ? tracker_->camera() : binloop::Tracker::savedCamera(path);
    auto fresh = std::make_shared<std::unique_ptr<binloop::Tracker>>(
        loadStage(std::make_unique<binloop::Tracker>(cam, config_.tracker), path, "tracking"));
    return PreparedLoad{[this, fresh] {
      startOver(std::move(*fresh));
      return std::to_string(tracker_->map().keyframeCount()) + " keyframes, " +
             std::to_string(tracker_->map().pointCount()) + " map points; lost until the next frames are relocalised";
    }};
  };
  h.reset = [this] {
    startOver(fixed_camera_ ? std::make_unique<binloop::Tracker>(*fixed_camera_, config_.tracker) : nullptr);
  };
  h.statistics = [this] {
    StageStatistics s{{"frames", std::to_string(frames_)}, {"frames_lost", std::to_string(lost_)},
                      {"input_dropped", std::to_string(rejected_)}, {"keyframes_sent", std::to_string(keyframes_sent_)}};
    if (tracker_) {
      s.emplace_back("state", binloop::msg::toString(tracker_->state()));
      s.emplace_back("keyframes", std::to_string(tracker_->map().keyframeCount()));
      s.emplace_back("map_points", std::to_string(tracker_->map().pointCount()));
    }
    return s;
  };
  services_ = std::make_unique<StageServices>(pnh, "tracking", h);
  last_pair_wall_ = ros::WallTime::now();  // no pair at all for ~stale_after_s is reported too
  NODELET_INFO("binloop/Tracking: %s sync on %s + %s, map frame '%s'", sync.c_str(), in_.left_image.c_str(),
               in_.right_image.c_str(), frames_out_->slamFrame().c_str());
}

// The map local mapping sent this (restarted) tracking: adopted by a tracker that has not started, or kept
// until the camera is known; a running tracker has its map already.
void TrackingNodelet::adopt(binloop::msg::LocalMapUpdatePtr whole) {
  if (!tracker_) {
    adopt_ = std::move(whole);
    return;
  }
  if (!tracker_->givesWayTo(*whole)) return;
  if (tracker_->state() != binloop::msg::TrackingState::kNotInitialized)
    startOver(std::make_unique<binloop::Tracker>(tracker_->camera(), config_.tracker));
  tracker_->adoptMap(*whole);
  ++maps_adopted_;
  NODELET_INFO("binloop/Tracking: took local mapping's map (%zu keyframes, %zu points): lost until the next frames "
               "are relocalised in it",
               tracker_->map().keyframeCount(), tracker_->map().pointCount());
}

// A loaded map or a reset: the tracker is replaced, and what the nodelet kept of the old one's frames goes.
void TrackingNodelet::startOver(std::unique_ptr<binloop::Tracker> t) {
  adopt_.reset();
  tracker_ = std::move(t);
  in_flight_.clear();
  frames_out_->restart();
  stamps_->reset();
  path_.poses.clear();
}

void TrackingNodelet::onInfo(const sensor_msgs::CameraInfoConstPtr& info, bool right) {
  CpuMeter::Scope cpu(cpu_);
  (right ? right_info_ : left_info_) = info;
  trackWaiting();
}

void TrackingNodelet::reject(const std::string& why) {
  ++rejected_;
  last_problem_ = why;
  NODELET_WARN_THROTTLE(1.0, "binloop/Tracking: stereo pair dropped: %s", why.c_str());
}

std::string TrackingNodelet::check(const Image& left, const Image& right) {
  last_stamp_diff_ = std::abs((left.header.stamp - right.header.stamp).toSec());
  if (last_stamp_diff_ > max_stamp_diff_)
    return "left and right stamps differ by " + std::to_string(last_stamp_diff_) + " s (more than ~max_stamp_diff " +
           std::to_string(max_stamp_diff_) + " s): not a synchronised pair";
  if (left.width != right.width || left.height != right.height)
    return "left is " + std::to_string(left.width) + "x" + std::to_string(left.height) + ", right " +
           std::to_string(right.width) + "x" + std::to_string(right.height);
  if (!tracker_) {
    if (!left_info_ || !right_info_)
      return std::string("no camera_info received yet on ") + (left_info_ ? in_.right_info : in_.left_info) +
             " (or give ~camera)";
    try {
      tracker_ = std::make_unique<binloop::Tracker>(toStereoCamera(*left_info_, *right_info_), config_.tracker);
      NODELET_INFO("binloop/Tracking: camera from camera_info:\n%s", toStereoCamera(*left_info_, *right_info_).describe().c_str());
      if (adopt_) adopt(std::exchange(adopt_, nullptr));
      const std::string distortion = distortionWarning(*left_info_);
      if (!distortion.empty()) NODELET_WARN("binloop/Tracking: %s", distortion.c_str());
    } catch (const std::exception& e) {
      left_info_.reset();  // wait for a usable pair
      return std::string("camera_info: ") + e.what();
    }
  }
  const auto& cam = tracker_->camera();
  if (static_cast<int>(left.width) != cam.width || static_cast<int>(left.height) != cam.height)
    return "image is " + std::to_string(left.width) + "x" + std::to_string(left.height) + ", the camera " +
           std::to_string(cam.width) + "x" + std::to_string(cam.height);
  // Last, as it counts the pairs it takes: the stamp.
  const StampGate::Decision time = stamps_->check(left.header.stamp.toSec());
  if (!time.taken()) return time.reason;
  if (time.verdict == StampGate::Verdict::kRestart) {
    tracker_->restartClock();
    frames_out_->clockWentBack();
    ++clock_restarts_;
    path_.poses.clear();
  }
  if (time.verdict != StampGate::Verdict::kTake) {
    last_problem_ = time.reason;
    NODELET_WARN("binloop/Tracking: %s", time.reason.c_str());
  }
  return "";
}

void TrackingNodelet::onImages(const sensor_msgs::ImageConstPtr& left, const sensor_msgs::ImageConstPtr& right) {
  CpuMeter::Scope cpu(cpu_);
  last_pair_wall_ = ros::WallTime::now();
  const std::string given_up = in_flight_.giveUpIfStale(last_pair_wall_.toSec(), keyframe_pub_.getNumSubscribers() > 0);
  if (!given_up.empty()) {
    last_problem_ = given_up;
    NODELET_WARN_THROTTLE(5.0, "binloop/Tracking: %s", last_problem_.c_str());
    trackWaiting();
  }
  // Pairs wait while there is no camera yet (camera_info may come just after the first images) and, in
  // lock-step, while mapping has not answered.
  const bool no_camera = !tracker_ && (!left_info_ || !right_info_);
  if (no_camera || (lockstep_ && (in_flight_.count() > 0 || !waiting_.empty()))) {
    waiting_.emplace_back(left, right);
    if (no_camera && waiting_.size() > 10) {
      waiting_.pop_front();
      reject(std::string("no camera_info received on ") + (left_info_ ? in_.right_info : in_.left_info) +
             " (or give ~camera)");
    } else if (waiting_.size() > max_waiting_) {
      waiting_.pop_front();
      reject("lock-step: " + std::to_string(max_waiting_) + " pairs already wait for local mapping; the oldest is dropped");
    }
    return;
  }
  track(left, right);
}

void TrackingNodelet::trackWaiting() {
  while (!waiting_.empty() && (tracker_ || (left_info_ && right_info_)) && !(lockstep_ && in_flight_.count() > 0)) {
    const auto pair = waiting_.front();
    waiting_.pop_front();
    track(pair.first, pair.second);
  }
}

void TrackingNodelet::track(const sensor_msgs::ImageConstPtr& left, const sensor_msgs::ImageConstPtr& right) {
  const ros::WallTime t0 = ros::WallTime::now();
  binloop::StereoFrame frame;
  std::string problem = check(*left, *right);
  if (problem.empty()) {
    try {
      frame.left = toGray(*left);
      frame.right = toGray(*right);
    } catch (const ConversionError& e) {
      problem = e.what();
    }
  }
  if (!problem.empty()) return reject(problem);
  frame.index = static_cast<int>(frames_++);
  frame.stamp_s = left->header.stamp.toSec();
  binloop::Tracker::Output out = tracker_->track(frame, in_flight_.count());
  if (out.frame.state == binloop::msg::TrackingState::kLost) ++lost_;
  if (!out.frame.problem.empty()) last_problem_ = out.frame.problem;
  if (out.keyframe) {
    in_flight_.sent(ros::WallTime::now().toSec());
    ++keyframes_sent_;
    keyframe_pub_.publish(boost::make_shared<binloop::KeyFrame>(toRos(*out.keyframe, frames_out_->slamFrame())));
  }
  frame_pub_.publish(boost::make_shared<binloop::TrackedFrame>(toRos(out.frame, frames_out_->slamFrame())));
  std_msgs::Header header = left->header;
  if (!camera_frame_.empty()) header.frame_id = camera_frame_;
  publishPose(out.frame, header);
  if (debug_pub_.getNumSubscribers() > 0) publishDebugImage(frame.left, out.frame, header);
  last_latency_ms_ = (ros::WallTime::now() - t0).toSec() * 1e3;
}

void TrackingNodelet::publishPose(const binloop::msg::TrackedFrame& f, const std_msgs::Header& header) {
  using binloop::msg::TrackingState;
  if (f.state == TrackingState::kNotInitialized || f.state == TrackingState::kLost) {
    frames_out_->lost(header.stamp);
    return;
  }
  frames_out_->tracked(f.T_w_c, f.pose_covariance, header.stamp, header.frame_id, corrections_ != corrections_at_last_);
  corrections_at_last_ = corrections_;
  const std::string problem = frames_out_->takeProblem();
  if (!problem.empty()) {
    last_problem_ = problem;
    NODELET_WARN_THROTTLE(5, "binloop/Tracking: %s", problem.c_str());
  }

  // The camera's pose in the slam frame, as the SLAM's other outputs.
  geometry_msgs::PoseStamped pose;
  pose.header.stamp = header.stamp;
  pose.header.frame_id = frames_out_->slamFrame();
  pose.pose = toPoseMsg(f.T_w_c);
  pose_pub_.publish(pose);

  // The live path: the last ~path_max_poses poses, serialised only for a subscriber (a whole drive's path
  // grew by a pose a frame and was re-sent every frame).
  path_.header = pose.header;
  path_.poses.push_back(pose);
  if (path_.poses.size() > path_max_poses_)
    path_.poses.erase(path_.poses.begin(), path_.poses.begin() + static_cast<long>(path_.poses.size() - path_max_poses_));
  if (path_pub_.getNumSubscribers() > 0) path_pub_.publish(path_);
}

// The left image with its features: green tracked (matched to a map point and an inlier), orange matched but
// rejected as an outlier, blue with a stereo match only, grey the rest; the state and counts on top.
void TrackingNodelet::publishDebugImage(const cv::Mat& gray, const binloop::msg::TrackedFrame& f,
                                        const std_msgs::Header& header) {
  cv::Mat img;
  cv::cvtColor(gray, img, cv::COLOR_GRAY2BGR);
  const binloop::Frame* last = tracker_->lastFrame();
  if (last && last->index == f.frame_index) {
    for (size_t i = 0; i < last->size(); ++i) {
      const auto& k = last->keypoints[i];
      cv::Scalar colour(150, 150, 150);
      if (last->points[i] != binloop::kNoId) colour = last->outlier[i] ? cv::Scalar(0, 140, 255) : cv::Scalar(0, 220, 0);
      else if (k.right_x >= 0) colour = cv::Scalar(255, 120, 0);
      cv::circle(img, cv::Point2f(k.x, k.y), 2 + k.octave, colour, 1, cv::LINE_AA);
    }
  }
  const std::string text = std::string(binloop::msg::toString(f.state)) + "  features " + std::to_string(f.features) +
                           "  stereo " + std::to_string(f.stereo_matches) + "  tracked " + std::to_string(f.tracked_points);
  cv::putText(img, text, cv::Point(10, 25), cv::FONT_HERSHEY_SIMPLEX, 0.7, cv::Scalar(0, 255, 255), 2, cv::LINE_AA);
  auto msg = boost::make_shared<sensor_msgs::Image>();
  msg->header = header;
  msg->height = img.rows;
  msg->width = img.cols;
  msg->encoding = "bgr8";
  msg->step = img.cols * 3;
  msg->data.assign(img.data, img.data + img.total() * 3);
  debug_pub_.publish(msg);
}

// The hint's radius is three standard deviations of its position (rviz sends 0.5 m), at least 5 m, as an
// operator clicks roughly, and at most 50 m.
void TrackingNodelet::onInitialPose(const geometry_msgs::PoseWithCovarianceStampedConstPtr& m) {
  if (!tracker_) return;
  const double var = std::max(m->pose.covariance[0], m->pose.covariance[7]);
  const double radius = std::clamp(3 * std::sqrt(std::max(var, 0.0)), 5.0, 50.0);
  try {
    const binloop::Pose3 T = frames_out_->hintInSlam(m->header.frame_id, toPose3(m->pose.pose));
    if (tracker_->state() != binloop::msg::TrackingState::kLost) {
      NODELET_INFO("binloop/Tracking: pose hint ignored: tracking is not lost");
      return;
    }
    tracker_->hintPose(T, radius);
    NODELET_INFO("binloop/Tracking: relocalising within %.1f m of the pose hint", radius);
  } catch (const std::exception& e) {
    last_problem_ = std::string("pose hint refused: ") + e.what();
    NODELET_WARN("binloop/Tracking: %s", last_problem_.c_str());
  }
}

void TrackingNodelet::onUpdate(const binloop::LocalMapUpdateConstPtr& m) {
  CpuMeter::Scope cpu(cpu_);
  try {
    binloop::msg::LocalMapUpdate u = fromRos(*m);
    if (u.whole_map) return adopt(std::make_shared<const binloop::msg::LocalMapUpdate>(std::move(u)));
    if (!tracker_) return;
    tracker_->apply(u);
    if (u.correction) {
      ++corrections_;
      in_flight_.heard(ros::WallTime::now().toSec());
    } else {
      in_flight_.answered(ros::WallTime::now().toSec());
    }
    trackWaiting();
  } catch (const std::exception& e) {
    ++rejected_;
    last_problem_ = std::string("local map update dropped: ") + e.what();
    NODELET_WARN_THROTTLE(1.0, "binloop/Tracking: %s", last_problem_.c_str());
  }
}

void TrackingNodelet::diagnose(diagnostic_updater::DiagnosticStatusWrapper& s) {
  const bool lost = tracker_ && tracker_->state() == binloop::msg::TrackingState::kLost;
  const double quiet_s = last_pair_wall_.isZero() ? 0 : (ros::WallTime::now() - last_pair_wall_).toSec();
  if (!tracker_) s.summary(diagnostic_msgs::DiagnosticStatus::WARN, "waiting for camera_info");
  else if (quiet_s > stale_after_s_)
    s.summary(diagnostic_msgs::DiagnosticStatus::WARN, "no stereo pair for " + std::to_string(static_cast<int>(quiet_s)) + " s");
  else if (guard_.failures() > 0) s.summary(diagnostic_msgs::DiagnosticStatus::WARN, "tracking; a callback failed");
  else if (in_flight_.givenUp() > 0)
    s.summary(diagnostic_msgs::DiagnosticStatus::WARN, "tracking; local mapping did not answer some keyframes");
  else if (lost) s.summary(diagnostic_msgs::DiagnosticStatus::WARN, "lost");
  else if (rejected_ > 0) s.summary(diagnostic_msgs::DiagnosticStatus::WARN, "tracking; some input dropped");
  else s.summary(diagnostic_msgs::DiagnosticStatus::OK, "tracking");
  s.add("frames tracked", frames_);
  s.add("frames lost", lost_);
  s.add("input dropped", rejected_);
  s.add("last problem", last_problem_);
  s.add("callbacks failed", guard_.failures());
  s.add("last callback failure", guard_.lastFailure());
  s.add("clock restarts", clock_restarts_);
  s.add("maps taken from local mapping", maps_adopted_);
  s.add("seconds since the last pair", quiet_s);
  s.add("keyframes sent", keyframes_sent_);
  s.add("mapping queue", in_flight_.count());
  s.add("keyframes given up (mapping did not answer)", in_flight_.givenUp());
  s.add("pairs waiting", waiting_.size());
  s.add("loop corrections applied", corrections_);
  s.add("stereo stamp difference s", last_stamp_diff_);
  s.add("processing ms (last frame)", last_latency_ms_);
  s.add("cpu s in callbacks", cpu_.seconds());
}

}  // namespace binloop_ros

PLUGINLIB_EXPORT_CLASS(binloop_ros::TrackingNodelet, nodelet::Nodelet)
