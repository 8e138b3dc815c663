#pragma once
// The rostests' drive: 1.25 laps round a 50 x 80 m block (one revisit), rendered once per test program and
// made into a bag by kitti2bag, and the bag's stereo pairs in stamp order.
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "binloop/io/trajectory_io.h"
#include "binloop/sim/builtin_route.h"
#include "binloop_ros/topics.h"
#include "support/test_support.h"

namespace binloop::test {

struct Drive {
  std::unique_ptr<binloop::test::TempDir> dir;
  std::vector<binloop::Pose3> route;
  std::string bag;
  std::string problem;  // why the drive could not be made
};

inline const Drive& drive() {
  static Drive d;
  if (d.dir) return d;
  d.dir = std::make_unique<binloop::test::TempDir>();
  d.route = binloop::sim::loopRoute(50, 80, 12, 8, 10, 1.25);
  binloop::writeKittiPoses(*d.dir / "route.txt", d.route);
  const std::string tools = BINLOOP_TOOL_DIR;
  auto r = binloop::test::runCommand(tools + "/render --route " + (*d.dir / "route.txt") +
                                     " --calib kitti04 --out " + (*d.dir / "seq"));
  if (r.code != 0) d.problem = "render failed: " + r.out;
  d.bag = *d.dir / "drive.bag";
  if (d.problem.empty()) {
    r = binloop::test::runCommand(tools + "/kitti2bag " + (*d.dir / "seq") + " " + d.bag);
    if (r.code != 0) d.problem = "kitti2bag failed: " + r.out;
  }
  return d;
}

/// Among `keyframe_at` (frame -> keyframe id) in the first stretch of the drive's first lap (up to 100 frames
/// before the revisit begins), the keyframe whose place is nearest to `metres_away` from frame
/// `query_frame`'s: (frame, keyframe id), or (0, 0) when there is none. 0 m: the keyframe a revisit should
/// close on.
inline std::pair<uint64_t, uint64_t> firstLapKeyframe(const Drive& d,
                                                      const std::map<uint64_t, uint64_t>& keyframe_at,
                                                      uint64_t query_frame, double metres_away) {
  const size_t lap = static_cast<size_t>(d.route.size() / 1.25);
  std::pair<uint64_t, uint64_t> best{0, 0};
  double best_gap = 1e9;
  for (const auto& [frame, id] : keyframe_at) {
    if (frame + 100 > lap) break;
    const double dist = (d.route[frame].translation() - d.route[query_frame].translation()).norm();
    if (std::abs(dist - metres_away) < best_gap) best_gap = std::abs(dist - metres_away), best = {frame, id};
  }
  return best;
}

struct Pair {
  sensor_msgs::Image left, right;
  sensor_msgs::CameraInfo left_info, right_info;
};

inline std::vector<Pair> readPairs(const std::string& path) {
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  std::map<ros::Time, Pair> by_stamp;
  for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
    if (auto img = m.instantiate<sensor_msgs::Image>()) {
      (m.getTopic() == binloop_ros::topics::kLeftImage ? by_stamp[img->header.stamp].left
                                                       : by_stamp[img->header.stamp].right) = *img;
    } else if (auto info = m.instantiate<sensor_msgs::CameraInfo>()) {
      (m.getTopic() == binloop_ros::topics::kLeftInfo ? by_stamp[info->header.stamp].left_info
                                                      : by_stamp[info->header.stamp].right_info) = *info;
    }
  }
  std::vector<Pair> out;
  for (auto& [stamp, p] : by_stamp) out.push_back(std::move(p));
  return out;
}

}  // namespace binloop::test
