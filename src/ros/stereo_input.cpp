#include "binloop_ros/stereo_input.h"

#include <opencv2/imgcodecs.hpp>

#include <cstring>
#include <stdexcept>

#include "binloop_ros/msg_conversion.h"

namespace binloop_ros {

namespace mf = message_filters;

sensor_msgs::ImageConstPtr decompress(const sensor_msgs::CompressedImage& m) {
  // image_transport's compressed format strings: "jpeg", "png", or "<encoding>; jpeg compressed bgr8".
  const bool known = m.format.find("jpeg") != std::string::npos ||
                     m.format.find("jpg") != std::string::npos || m.format.find("png") != std::string::npos;
  if (!known)
    throw ConversionError("compressed image format '" + m.format + "': only jpeg and png are decoded");
  if (m.data.empty()) throw ConversionError("compressed image with no bytes");
  const cv::Mat bytes(1, static_cast<int>(m.data.size()), CV_8UC1, const_cast<uint8_t*>(m.data.data()));
  const cv::Mat img = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
  if (img.empty())
    throw ConversionError("compressed image (" + m.format + ", " + std::to_string(m.data.size()) +
                          " bytes) does not decode");
  if (img.depth() != CV_8U || (img.channels() != 1 && img.channels() != 3))
    throw ConversionError("compressed image decodes to " + std::to_string(img.channels()) + " channels of " +
                          (img.depth() == CV_8U ? "8" : "more than 8") +
                          " bits; expected 8-bit grey or colour");
  auto out = boost::make_shared<sensor_msgs::Image>();
  out->header = m.header;
  out->height = static_cast<uint32_t>(img.rows);
  out->width = static_cast<uint32_t>(img.cols);
  out->encoding = img.channels() == 1 ? "mono8" : "bgr8";
  out->step = static_cast<uint32_t>(img.cols * img.channels());
  out->data.resize(static_cast<size_t>(out->step) * img.rows);
  for (int r = 0; r < img.rows; ++r)
    std::memcpy(&out->data[static_cast<size_t>(r) * out->step], img.ptr(r), out->step);
  return out;
}

template <class M>
void StereoInput::connect(Pairing<M>& p, ros::NodeHandle& nh, const std::string& left,
                          const std::string& right, bool exact, int queue,
                          void (StereoInput::*callback)(const boost::shared_ptr<const M>&,
                                                        const boost::shared_ptr<const M>&)) {
  // message_filters' synchronizers bind a member function (with nine arguments), not a generic callable.
  p.left.subscribe(nh, left, queue);
  p.right.subscribe(nh, right, queue);
  if (exact) {
    p.exact = std::make_unique<mf::Synchronizer<mf::sync_policies::ExactTime<M, M>>>(
        mf::sync_policies::ExactTime<M, M>(queue), p.left, p.right);
    p.exact->registerCallback(callback, this);
  } else {
    p.approx = std::make_unique<mf::Synchronizer<mf::sync_policies::ApproximateTime<M, M>>>(
        mf::sync_policies::ApproximateTime<M, M>(queue), p.left, p.right);
    p.approx->registerCallback(callback, this);
  }
}

void StereoInput::onRaw(const sensor_msgs::ImageConstPtr& l, const sensor_msgs::ImageConstPtr& r) {
  on_pair_(l, r);
}

void StereoInput::onCompressed(const sensor_msgs::CompressedImageConstPtr& l,
                               const sensor_msgs::CompressedImageConstPtr& r) {
  sensor_msgs::ImageConstPtr left, right;
  try {
    left = decompress(*l);
    right = decompress(*r);
  } catch (const ConversionError& e) {
    on_bad_(e.what());
    return;
  }
  on_pair_(left, right);
}

StereoInput::StereoInput(ros::NodeHandle& nh, const std::string& left_topic, const std::string& right_topic,
                         const std::string& transport, const std::string& sync, int queue,
                         PairCallback on_pair, BadCallback on_bad)
    : on_pair_(std::move(on_pair)), on_bad_(std::move(on_bad)) {
  if (sync != "exact" && sync != "approximate")
    throw std::invalid_argument("~sync '" + sync + "': exact or approximate");
  const bool exact = sync == "exact";
  if (transport == "raw") {
    connect(raw_, nh, left_topic, right_topic, exact, queue, &StereoInput::onRaw);
  } else if (transport == "compressed") {
    connect(compressed_, nh, left_topic + "/compressed", right_topic + "/compressed", exact, queue,
            &StereoInput::onCompressed);
  } else {
    throw std::invalid_argument("~transport '" + transport + "': raw or compressed");
  }
}

}  // namespace binloop_ros
