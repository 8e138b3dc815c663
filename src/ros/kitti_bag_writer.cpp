#include "binloop_ros/kitti_bag_writer.h"

#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <sensor_msgs/CompressedImage.h>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "binloop_ros/msg_conversion.h"
#include "binloop_ros/topics.h"

namespace fs = std::filesystem;

namespace binloop_ros {

namespace {

sensor_msgs::CompressedImage pngMsg(const cv::Mat& img, const ros::Time& stamp, const std::string& frame) {
  sensor_msgs::CompressedImage m;
  m.header.stamp = stamp;
  m.header.frame_id = frame;
  m.format = "mono8; png compressed ";  // image_transport's compressed transport's format string
  if (!cv::imencode(".png", img, m.data)) throw std::runtime_error("PNG encoding failed");
  return m;
}

}  // namespace

KittiBagSummary writeKittiBag(const binloop::KittiSequence& seq, const std::string& out,
                              const KittiBagOptions& opt,
                              const std::function<void(size_t, size_t)>& progress) {
  if (!opt.overwrite && fs::exists(out))
    throw std::runtime_error(out + ": already exists (use --force to overwrite)");
  if (opt.start >= seq.size())
    throw std::runtime_error("start frame " + std::to_string(opt.start) + " is past the sequence end (" +
                             std::to_string(seq.size()) + " frames)");
  const size_t last = std::min(opt.end, seq.size() - 1);
  if (last < opt.start) throw std::runtime_error("end frame is before start frame");

  const std::string partial = out + ".partial";
  KittiBagSummary sum;
  try {
    rosbag::Bag bag(partial, rosbag::bagmode::Write);
    if (opt.lz4) bag.setCompression(rosbag::compression::LZ4);
    const size_t total = last - opt.start + 1;
    auto left_info = toCameraInfo(seq.camera(), false, ros::Time(), topics::kLeftFrame);
    auto right_info = toCameraInfo(seq.camera(), true, ros::Time(), topics::kRightFrame);
    for (size_t i = opt.start; i <= last; ++i) {
      const auto frame = seq.load(i);
      const ros::Time stamp = toRosTime(frame.stamp_s + opt.stamp_offset_s);
      if (opt.png) {
        bag.write(std::string(topics::kLeftImage) + "/compressed", stamp,
                  pngMsg(frame.left, stamp, topics::kLeftFrame));
        bag.write(std::string(topics::kRightImage) + "/compressed", stamp,
                  pngMsg(frame.right, stamp, topics::kRightFrame));
      } else {
        bag.write(topics::kLeftImage, stamp, toImageMsg(frame.left, stamp, topics::kLeftFrame));
      }
      left_info.header.stamp = right_info.header.stamp = stamp;
      bag.write(topics::kLeftInfo, stamp, left_info);
      bag.write(topics::kRightImage, stamp, toImageMsg(frame.right, stamp, topics::kRightFrame));
      bag.write(topics::kRightInfo, stamp, right_info);
      if (seq.hasPoses()) {
        nav_msgs::Odometry odom;
        odom.header.stamp = stamp;
        odom.header.frame_id = topics::kGroundTruthFrame;
        odom.child_frame_id = topics::kLeftFrame;
        odom.pose.pose = toPoseMsg(seq.poses()[i]);
        bag.write(topics::kGroundTruth, stamp, odom);
        ++sum.ground_truth;
      }
      if (sum.frames == 0) sum.first_stamp = stamp.toSec();
      sum.last_stamp = stamp.toSec();
      ++sum.frames;
      if (progress) progress(sum.frames, total);
    }
    bag.close();
  } catch (...) {
    std::error_code ec;
    fs::remove(partial, ec);
    throw;
  }
  fs::rename(partial, out);
  sum.bytes = fs::file_size(out);
  return sum;
}

}  // namespace binloop_ros
