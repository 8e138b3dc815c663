#include "binloop/features/orb_extractor.h"

#include <opencv2/features2d.hpp>

#include "binloop/place/place_error.h"

namespace binloop {

OrbFeatures extractOrb(const cv::Mat& gray, const OrbParams& p) {
  if (gray.empty()) throw PlaceError("cannot extract ORB features from an empty image");
  if (gray.type() != CV_8UC1) throw PlaceError("ORB needs an 8-bit single-channel (grey) image");
  auto orb = cv::ORB::create(p.features, p.scale_factor, p.levels, 31, 0, 2, cv::ORB::HARRIS_SCORE, 31,
                             p.fast_threshold);
  OrbFeatures out;
  cv::Mat desc;
  orb->detectAndCompute(gray, cv::noArray(), out.keypoints, desc);
  out.descriptors = descriptorsFromMat(desc);
  return out;
}

}  // namespace binloop
