#pragma once
// The exception type of feature extraction and stereo matching: an image the extractor cannot take, settings
// out of range, an unknown test pattern. (Place recognition, above it, has its own: place/place_error.h.)
#include <stdexcept>

namespace binloop {

class FeatureError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace binloop
