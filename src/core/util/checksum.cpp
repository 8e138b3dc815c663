#include "binloop/util/checksum.h"

#include <cstring>

#include "binloop/util/hash_random.h"

namespace binloop {

uint64_t checksum64(const void* data, size_t n) {
  // xxHash64's round on four lanes (our code, its constants): the lanes do not wait for each other.
  constexpr uint64_t kP1 = 0x9E3779B185EBCA87ull, kP2 = 0xC2B2AE3D27D4EB4Full;
  const auto rotl = [](uint64_t x, int r) { return (x << r) | (x >> (64 - r)); };
  const auto* p = static_cast<const uint8_t*>(data);
  uint64_t lane[4] = {kP1 + kP2, kP2, 0, 0 - kP1};
  size_t i = 0;
  for (; i + 32 <= n; i += 32) {
    for (int l = 0; l < 4; ++l) {
      uint64_t w;
      std::memcpy(&w, p + i + 8 * static_cast<size_t>(l), 8);
      lane[l] = rotl(lane[l] + w * kP2, 31) * kP1;
    }
  }
  uint64_t h = n;
  for (int l = 0; l < 4; ++l) h = splitmix64(h ^ lane[l]);
  uint64_t tail[4] = {0, 0, 0, 0};
  if (n > i) std::memcpy(tail, p + i, n - i);  // an empty section may have no pointer at all
  for (uint64_t t : tail) h = splitmix64(h ^ t);
  return h;
}

}  // namespace binloop
