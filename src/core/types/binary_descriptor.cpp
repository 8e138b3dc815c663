#include "binloop/types/binary_descriptor.h"

#include <cstring>
#include <string>

#include "binloop/place/place_error.h"

namespace binloop {

Desc256 descriptorFromBytes(const uint8_t* bytes) {
  Desc256 d;
  std::memcpy(d.w.data(), bytes, Desc256::kBytes);  // little-endian: byte i holds bits 8i..8i+7
  return d;
}

Descriptors descriptorsFromMat(const cv::Mat& rows) {
  if (rows.empty()) return {};
  if (rows.depth() != CV_8U || rows.channels() != 1 || rows.cols != Desc256::kBytes) {
    throw PlaceError("descriptors must be 32-byte binary rows (CV_8U, 32 columns, as ORB gives); got " +
                     std::to_string(rows.cols) + " columns of depth " + std::to_string(rows.depth()) +
                     " with " + std::to_string(rows.channels()) + " channel(s)");
  }
  Descriptors out(rows.rows);
  for (int r = 0; r < rows.rows; ++r) out[r] = descriptorFromBytes(rows.ptr<uint8_t>(r));
  return out;
}

}  // namespace binloop
