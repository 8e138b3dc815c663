#pragma once
// The one exception type of place recognition: bad descriptors, bad model files, bad parameters.
#include <stdexcept>

namespace binloop {

class PlaceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace binloop
