#pragma once
// A 256-bit binary descriptor (ORB) held as four 64-bit words, so that a Hamming distance is four
// popcounts instead of a loop over 32 bytes. Byte order matches OpenCV's 32-byte rows: bit b of the
// descriptor is bit (b % 8) of byte (b / 8).
#include <array>
#include <cstdint>
#include <vector>

#include <opencv2/core/mat.hpp>

namespace binloop {

struct Desc256 {
  std::array<uint64_t, 4> w{};

  static constexpr int kBits = 256;
  static constexpr int kBytes = 32;

  bool bit(int b) const { return (w[b >> 6] >> (b & 63)) & 1u; }
  void setBit(int b) { w[b >> 6] |= uint64_t{1} << (b & 63); }
  bool operator==(const Desc256& o) const { return w == o.w; }
  bool operator<(const Desc256& o) const { return w < o.w; }
};

inline int hamming(const Desc256& a, const Desc256& b) {
  return __builtin_popcountll(a.w[0] ^ b.w[0]) + __builtin_popcountll(a.w[1] ^ b.w[1]) +
         __builtin_popcountll(a.w[2] ^ b.w[2]) + __builtin_popcountll(a.w[3] ^ b.w[3]);
}

using Descriptors = std::vector<Desc256>;

/// Rows of a CV_8U matrix with 32 columns (OpenCV's ORB output). Throws PlaceError naming the size
/// or type found otherwise; an empty matrix gives an empty set.
Descriptors descriptorsFromMat(const cv::Mat& rows);

/// From 32 raw bytes, in OpenCV's order.
Desc256 descriptorFromBytes(const uint8_t* bytes);

}  // namespace binloop
