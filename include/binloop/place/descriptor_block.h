#pragma once
// A set of descriptors searched by brute force for one query's nearest and second-nearest (loop
// verification: ~2000 x 2000 Hamming distances per candidate). They are stored word by word (four arrays:
// every descriptor's first 64 bits, then every second 64 bits, ...), so that eight candidates are one
// 512-bit load per word; on CPUs with AVX-512 VPOPCNTDQ the search runs eight distances at a time, elsewhere
// one at a time. Both give the same answer: ties go to the lowest index.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "binloop/types/binary_descriptor.h"

namespace binloop {

class DescriptorBlock {
 public:
  struct Nearest {
    int index = -1;    // into the block; -1 when it is empty
    int best = 256;    // Hamming distance to it
    int second = 256;  // to the next nearest (256 when there is none); equal to best on a tie
  };

  DescriptorBlock() = default;
  explicit DescriptorBlock(const Descriptors& d);
  void add(const Desc256& d);
  size_t size() const { return words_[0].size(); }

  Nearest nearest(const Desc256& q) const;
  /// The plain loop, whatever the CPU (for the tests, to compare the two).
  Nearest nearestPortable(const Desc256& q) const;
  /// Whether nearest() uses the eight-wide search on this CPU.
  static bool wide();

 private:
  std::vector<uint64_t> words_[4];
};

}  // namespace binloop
