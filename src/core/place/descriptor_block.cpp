#include "binloop/place/descriptor_block.h"

// GCC 12's own AVX-512 headers trip -Wmaybe-uninitialized (their _mm512_undefined_* placeholders); clang
// (clang-tidy) has no such warning.
#pragma GCC diagnostic push
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <immintrin.h>

#include <limits>

namespace binloop {
namespace {

// A distance and an index packed so that one unsigned comparison orders by distance, then by index.
uint64_t pack(uint64_t distance, uint64_t index) { return distance << 32 | index; }

DescriptorBlock::Nearest unpack(uint64_t first, uint64_t second) {
  DescriptorBlock::Nearest n;
  constexpr uint64_t kNone = std::numeric_limits<uint64_t>::max();
  if (first == kNone) return n;
  n.index = static_cast<int>(first & 0xffffffffu);
  n.best = static_cast<int>(first >> 32);
  n.second = second == kNone ? 256 : static_cast<int>(second >> 32);
  return n;
}

// Each of the eight lanes keeps its two smallest packed values; the two smallest overall are among those 16.
__attribute__((target("avx512f,avx512vpopcntdq"))) DescriptorBlock::Nearest nearestWide(
    const std::vector<uint64_t>* words, const Desc256& q) {
  const size_t n = words[0].size();
  const __m512i q0 = _mm512_set1_epi64(static_cast<long long>(q.w[0]));
  const __m512i q1 = _mm512_set1_epi64(static_cast<long long>(q.w[1]));
  const __m512i q2 = _mm512_set1_epi64(static_cast<long long>(q.w[2]));
  const __m512i q3 = _mm512_set1_epi64(static_cast<long long>(q.w[3]));
  const __m512i none = _mm512_set1_epi64(-1);
  const __m512i eight = _mm512_set1_epi64(8);
  __m512i index = _mm512_setr_epi64(0, 1, 2, 3, 4, 5, 6, 7);
  __m512i m1 = none, m2 = none;
  for (size_t k = 0; k < n; k += 8) {
    const __mmask8 in = n - k >= 8 ? 0xff : static_cast<__mmask8>((1u << (n - k)) - 1);
    __m512i d = _mm512_popcnt_epi64(_mm512_xor_si512(_mm512_maskz_loadu_epi64(in, words[0].data() + k), q0));
    d = _mm512_add_epi64(
        d, _mm512_popcnt_epi64(_mm512_xor_si512(_mm512_maskz_loadu_epi64(in, words[1].data() + k), q1)));
    d = _mm512_add_epi64(
        d, _mm512_popcnt_epi64(_mm512_xor_si512(_mm512_maskz_loadu_epi64(in, words[2].data() + k), q2)));
    d = _mm512_add_epi64(
        d, _mm512_popcnt_epi64(_mm512_xor_si512(_mm512_maskz_loadu_epi64(in, words[3].data() + k), q3)));
    const __m512i v = _mm512_mask_mov_epi64(none, in, _mm512_or_si512(_mm512_slli_epi64(d, 32), index));
    m2 = _mm512_min_epu64(m2, _mm512_max_epu64(m1, v));
    m1 = _mm512_min_epu64(m1, v);
    index = _mm512_add_epi64(index, eight);
  }
  alignas(64) uint64_t lanes[16];
  _mm512_store_si512(lanes, m1);
  _mm512_store_si512(lanes + 8, m2);
  uint64_t first = std::numeric_limits<uint64_t>::max(), second = first;
  for (uint64_t v : lanes) {
    if (v < first) {
      second = first, first = v;
    } else if (v < second) {
      second = v;
    }
  }
  return unpack(first, second);
}

}  // namespace
#pragma GCC diagnostic pop

DescriptorBlock::DescriptorBlock(const Descriptors& d) {
  for (auto& w : words_) w.reserve(d.size());
  for (const Desc256& x : d) add(x);
}

void DescriptorBlock::add(const Desc256& d) {
  for (int i = 0; i < 4; ++i) words_[i].push_back(d.w[i]);
}

bool DescriptorBlock::wide() {
  static const bool yes = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vpopcntdq");
  return yes;
}

DescriptorBlock::Nearest DescriptorBlock::nearest(const Desc256& q) const {
  return wide() ? nearestWide(words_, q) : nearestPortable(q);
}

DescriptorBlock::Nearest DescriptorBlock::nearestPortable(const Desc256& q) const {
  uint64_t first = std::numeric_limits<uint64_t>::max(), second = first;
  for (size_t k = 0; k < size(); ++k) {
    const int d = __builtin_popcountll(q.w[0] ^ words_[0][k]) + __builtin_popcountll(q.w[1] ^ words_[1][k]) +
                  __builtin_popcountll(q.w[2] ^ words_[2][k]) + __builtin_popcountll(q.w[3] ^ words_[3][k]);
    const uint64_t v = pack(static_cast<uint64_t>(d), k);
    if (v < second) {
      if (v < first) {
        second = first, first = v;
      } else {
        second = v;
      }
    }
  }
  return unpack(first, second);
}

}  // namespace binloop
