#pragma once
// The Tracking nodelet's image input: the left and right images paired by stamp (exactly, or approximately
// for rigs without hardware sync), as raw sensor_msgs/Image or as JPEG/PNG sensor_msgs/CompressedImage on
// the raw topics' `/compressed` (what image_transport's compressed transport publishes, and what bags
// recorded from it hold). Compressed pairs are decoded here, so the tracker sees Images either way.
#include <message_filters/subscriber.h>
#include <message_filters/sync_policies/approximate_time.h>
#include <message_filters/sync_policies/exact_time.h>
#include <message_filters/synchronizer.h>
#include <ros/ros.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>

#include <functional>
#include <memory>
#include <string>

namespace binloop_ros {

/// A JPEG or PNG CompressedImage as a mono8 (grey) or bgr8 (colour) Image with the same header. Throws
/// ConversionError naming what is wrong (an unknown format, bytes that do not decode).
sensor_msgs::ImageConstPtr decompress(const sensor_msgs::CompressedImage& m);

class StereoInput {
 public:
  using PairCallback =
      std::function<void(const sensor_msgs::ImageConstPtr&, const sensor_msgs::ImageConstPtr&)>;
  /// A pair that could not be made into Images (compressed bytes that do not decode), with the reason.
  using BadCallback = std::function<void(const std::string&)>;

  /// `transport`: raw or compressed; `sync`: exact or approximate. Throws std::invalid_argument for others.
  StereoInput(ros::NodeHandle& nh, const std::string& left_topic, const std::string& right_topic,
              const std::string& transport, const std::string& sync, int queue, PairCallback on_pair,
              BadCallback on_bad);

 private:
  template <class M>
  struct Pairing {
    message_filters::Subscriber<M> left, right;
    std::unique_ptr<message_filters::Synchronizer<message_filters::sync_policies::ExactTime<M, M>>> exact;
    std::unique_ptr<message_filters::Synchronizer<message_filters::sync_policies::ApproximateTime<M, M>>>
        approx;
  };
  template <class M>
  void connect(Pairing<M>& p, ros::NodeHandle& nh, const std::string& left, const std::string& right,
               bool exact, int queue,
               void (StereoInput::*callback)(const boost::shared_ptr<const M>&,
                                             const boost::shared_ptr<const M>&));
  void onRaw(const sensor_msgs::ImageConstPtr& l, const sensor_msgs::ImageConstPtr& r);
  void onCompressed(const sensor_msgs::CompressedImageConstPtr& l,
                    const sensor_msgs::CompressedImageConstPtr& r);

  PairCallback on_pair_;
  BadCallback on_bad_;
  Pairing<sensor_msgs::Image> raw_;
  Pairing<sensor_msgs::CompressedImage> compressed_;
};

}  // namespace binloop_ros
