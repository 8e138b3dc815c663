#pragma once
// What a rostest node sees of a binloop graph: publishers of stereo pairs on the graph's default input
// topics, and everything the graph publishes (poses, loops, candidates, odometry, diagnostics) collected on
// the spinner's thread. The rostest programs derive their fixtures from GraphTest.
#include <binloop/LoopCandidates.h>
#include <binloop/LoopClosure.h>
#include <binloop/Statistics.h>
#include <diagnostic_msgs/DiagnosticArray.h>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "binloop_ros/topics.h"

namespace binloop::test {

// What the graph publishes, collected on the spinner's thread.
struct Observed {
  std::mutex m;
  std::map<double, geometry_msgs::Pose> poses;  // by stamp
  std::vector<double> pose_stamps;              // every pose message's stamp, in order
  std::vector<binloop::LoopClosure> closures;
  std::vector<binloop::LoopCandidates> candidates;
  nav_msgs::Path corrected_path;
  std::vector<nav_msgs::Odometry> odometry;
  std::vector<geometry_msgs::PoseWithCovarianceStamped> poses_with_covariance;
  std::map<std::string, std::map<std::string, std::string>>
      diag;  // every stage's last values, by status name

  // A value of the tracking stage's diagnostics (the status whose name says "tracking"), "" before it came;
  // the caller holds `m`.
  std::string tracking(const std::string& key) const {
    for (const auto& [name, values] : diag)
      if (name.find("tracking") != std::string::npos)
        if (auto it = values.find(key); it != values.end()) return it->second;
    return "";
  }
  long trackingCount(const std::string& key) const {
    const std::string v = tracking(key);
    return v.empty() ? 0 : std::stol(v);
  }
};

class GraphTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ros::NodeHandle nh;
    left_ = nh.advertise<sensor_msgs::Image>(binloop_ros::topics::kLeftImage, 10);
    right_ = nh.advertise<sensor_msgs::Image>(binloop_ros::topics::kRightImage, 10);
    left_info_ = nh.advertise<sensor_msgs::CameraInfo>(binloop_ros::topics::kLeftInfo, 10);
    right_info_ = nh.advertise<sensor_msgs::CameraInfo>(binloop_ros::topics::kRightInfo, 10);
    subs_.push_back(nh.subscribe<geometry_msgs::PoseStamped>("/binloop/pose", 1000, [this](const auto& m) {
      std::lock_guard<std::mutex> lk(seen_.m);
      seen_.poses[m->header.stamp.toSec()] = m->pose;
      seen_.pose_stamps.push_back(m->header.stamp.toSec());
    }));
    subs_.push_back(nh.subscribe<binloop::LoopClosure>("/binloop/loop_closure", 100, [this](const auto& m) {
      std::lock_guard<std::mutex> lk(seen_.m);
      seen_.closures.push_back(*m);
    }));
    subs_.push_back(
        nh.subscribe<binloop::LoopCandidates>("/binloop/loop_candidates", 1000, [this](const auto& m) {
          std::lock_guard<std::mutex> lk(seen_.m);
          seen_.candidates.push_back(*m);
        }));
    subs_.push_back(nh.subscribe<geometry_msgs::PoseWithCovarianceStamped>(
        "/binloop/pose_with_covariance", 1000, [this](const auto& m) {
          std::lock_guard<std::mutex> lk(seen_.m);
          seen_.poses_with_covariance.push_back(*m);
        }));
    subs_.push_back(nh.subscribe<nav_msgs::Odometry>("/binloop/odom", 1000, [this](const auto& m) {
      std::lock_guard<std::mutex> lk(seen_.m);
      seen_.odometry.push_back(*m);
    }));
    subs_.push_back(nh.subscribe<nav_msgs::Path>("/binloop/corrected_path", 10, [this](const auto& m) {
      std::lock_guard<std::mutex> lk(seen_.m);
      seen_.corrected_path = *m;
    }));
    subs_.push_back(
        nh.subscribe<diagnostic_msgs::DiagnosticArray>("/diagnostics", 100, [this](const auto& m) {
          std::lock_guard<std::mutex> lk(seen_.m);
          for (const auto& s : m->status)
            for (const auto& kv : s.values) seen_.diag[s.name][kv.key] = kv.value;
        }));
  }

  // Waits for `pred` (checked under the lock) up to `seconds`.
  template <class Pred>
  bool waitFor(double seconds, Pred pred) {
    const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(seconds);
    while (ros::ok() && ros::WallTime::now() < until) {
      {
        std::lock_guard<std::mutex> lk(seen_.m);
        if (pred()) return true;
      }
      ros::WallDuration(0.005).sleep();
    }
    return false;
  }

  bool graphConnected() {
    return waitFor(60, [&] {
      return left_.getNumSubscribers() > 0 && right_.getNumSubscribers() > 0 &&
             left_info_.getNumSubscribers() > 0;
    });
  }

  void publishPair(const sensor_msgs::Image& l, const sensor_msgs::Image& r,
                   const sensor_msgs::CameraInfo& li, const sensor_msgs::CameraInfo& ri) {
    left_info_.publish(li);
    right_info_.publish(ri);
    left_.publish(l);
    right_.publish(r);
  }

  // No callback may run once the fixture is going: the spinner's threads would write into members already
  // destroyed (a derived fixture's are destroyed first, then seen_). Shutting a subscriber down waits for
  // its callback in progress. (A second test once crashed with SIGSEGV at its start without this.)
  void TearDown() override {
    for (ros::Subscriber& s : subs_) s.shutdown();
  }

  ros::Publisher left_, right_, left_info_, right_info_;
  Observed seen_;
  std::vector<ros::Subscriber> subs_;  // after seen_: destroyed before it
};

/// /binloop/statistics as key -> value; empty when the service does not answer.
inline std::map<std::string, std::string> statistics() {
  binloop::Statistics srv;
  std::map<std::string, std::string> out;
  if (!ros::service::call("/binloop/statistics", srv)) return out;
  for (const auto& kv : srv.response.values) out[kv.key] = kv.value;
  return out;
}

}  // namespace binloop::test
