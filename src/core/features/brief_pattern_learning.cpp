#include "binloop/features/brief_pattern_learning.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numeric>
#include <string>
#include <thread>

#include "binloop/features/feature_error.h"
#include "binloop/util/hash_random.h"

namespace binloop {

namespace {

constexpr int kRadius = 15;

// Runs f(i) for i in [0, n) on `threads` threads; f must only write its own slots.
template <class F>
void parallelFor(size_t n, int threads, F f) {
  std::atomic<size_t> next{0};
  auto work = [&] {
    for (size_t i; (i = next++) < n;) f(i);
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::max(1, threads); ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
}

struct Candidate {
  uint16_t a, b;  // disc point indices; bit = value[a] < value[b]
  double mean;
  double ties;  // share of keypoints with |value[a] - value[b]| <= tie_margin
};

size_t discIndex(int x, int y) {
  const auto& d = briefDisc();
  const auto it = std::find(d.begin(), d.end(), cv::Point(x, y));
  if (it == d.end()) {
    throw FeatureError("test point (" + std::to_string(x) + ", " + std::to_string(y) +
                       ") is outside the radius-15 disc");
  }
  return static_cast<size_t>(it - d.begin());
}

}  // namespace

const std::vector<cv::Point>& briefDisc() {
  static const std::vector<cv::Point> disc = [] {
    std::vector<cv::Point> d;
    for (int y = -kRadius; y <= kRadius; ++y) {
      for (int x = -kRadius; x <= kRadius; ++x)
        if (x * x + y * y <= kRadius * kRadius) d.emplace_back(x, y);
    }
    return d;
  }();
  return disc;
}

void PatchSamples::append(const PatchSamples& more) {
  if (more.values.empty()) return;
  if (values.empty()) values.resize(more.values.size());
  for (size_t p = 0; p < values.size(); ++p)
    values[p].insert(values[p].end(), more.values[p].begin(), more.values[p].end());
}

PatchSamples samplePatches(const cv::Mat& gray, const OrbSlamExtractor& extractor, size_t max_keypoints,
                           uint64_t seed) {
  const ImagePyramid pyr = extractor.pyramid(gray);
  const OrbFeatures f = extractor.extract(pyr);
  // Which keypoints: a seeded partial shuffle, then back into extraction order.
  std::vector<size_t> pick(f.keypoints.size());
  std::iota(pick.begin(), pick.end(), 0);
  if (pick.size() > max_keypoints) {
    HashRng rng(seed);
    for (size_t i = 0; i < max_keypoints; ++i)
      std::swap(pick[i], pick[i + static_cast<size_t>(rng.below(static_cast<int>(pick.size() - i)))]);
    pick.resize(max_keypoints);
    std::sort(pick.begin(), pick.end());
  }
  const auto& disc = briefDisc();
  PatchSamples s;
  s.values.assign(disc.size(), std::vector<uint8_t>(pick.size()));
  std::vector<cv::Mat> smoothed(pyr.levels.size());
  for (size_t j = 0; j < pick.size(); ++j) {
    const cv::KeyPoint& k = f.keypoints[pick[j]];
    const size_t level = static_cast<size_t>(k.octave);
    if (smoothed[level].empty()) briefSmoothed(pyr.levels[level], smoothed[level]);
    const cv::Mat& img = smoothed[level];
    // The extractor works in level pixels and scales the point to level 0 afterwards; level points are
    // whole pixels, so rounding recovers them exactly.
    const float scale = pyr.scale[level];
    const cv::Point c(cvRound(k.pt.x / scale), cvRound(k.pt.y / scale));
    float cs, sn;
    briefRotation(k.angle, &cs, &sn);
    for (size_t p = 0; p < disc.size(); ++p) {
      const cv::Point q =
          c + rotatedTestPoint(static_cast<float>(disc[p].x), static_cast<float>(disc[p].y), cs, sn);
      s.values[p][j] = img.at<uint8_t>(q.y, q.x);
    }
  }
  return s;
}

std::vector<uint8_t> testBits(const PatchSamples& s, const BriefTest& t) {
  const auto& a = s.values.at(discIndex(t.ax, t.ay));
  const auto& b = s.values.at(discIndex(t.bx, t.by));
  std::vector<uint8_t> bits(a.size());
  for (size_t k = 0; k < a.size(); ++k) bits[k] = a[k] < b[k];
  return bits;
}

namespace {

void checkInput(const PatchSamples& s, const PatternLearningOptions& o) {
  if (s.keypoints() == 0 || s.values.size() != briefDisc().size())
    throw FeatureError("no patch samples to learn a pattern from");
  if (o.bits < 1 || o.min_separation < 0 || o.start_threshold <= 0 || o.threshold_step <= 0 ||
      o.pool < size_t(o.bits) || o.tie_margin < 0 || o.max_tie_share <= 0) {
    throw FeatureError(
        "pattern learning options out of range (bits >= 1, min_separation >= 0, thresholds > 0, "
        "pool >= bits, tie_margin >= 0, max_tie_share > 0)");
  }
}

// 1-3. Every test between disc points at least o.min_separation apart: its share of a < b and b < a (ties
// count for neither), oriented so that its mean is the nearer to 0.5, and its share of near-ties.
std::vector<Candidate> scoreCandidates(const PatchSamples& s, const PatternLearningOptions& o) {
  const auto& disc = briefDisc();
  const size_t n = s.keypoints();
  std::vector<std::pair<uint16_t, uint16_t>> pairs;
  for (size_t a = 0; a < disc.size(); ++a) {
    for (size_t b = a + 1; b < disc.size(); ++b) {
      if (std::max(std::abs(disc[a].x - disc[b].x), std::abs(disc[a].y - disc[b].y)) >= o.min_separation)
        pairs.emplace_back(static_cast<uint16_t>(a), static_cast<uint16_t>(b));
    }
  }
  std::vector<Candidate> cand(pairs.size());
  parallelFor((pairs.size() + 255) / 256, o.threads, [&](size_t block) {
    const size_t end = std::min(pairs.size(), 256 * block + 256);
    for (size_t i = 256 * block; i < end; ++i) {
      const uint8_t* va = s.values[pairs[i].first].data();
      const uint8_t* vb = s.values[pairs[i].second].data();
      const int margin = o.tie_margin;
      uint32_t lt = 0, gt = 0, near = 0;
      for (size_t k = 0; k < n; ++k) {
        lt += va[k] < vb[k];
        gt += va[k] > vb[k];
        near += std::abs(int(va[k]) - int(vb[k])) <= margin;
      }
      // 3. Orient the test so that its mean is the nearer to 0.5 (ties make the two differ).
      const double m_lt = double(lt) / n, m_gt = double(gt) / n, ties = double(near) / n;
      cand[i] = std::abs(m_lt - 0.5) <= std::abs(m_gt - 0.5)
                    ? Candidate{pairs[i].first, pairs[i].second, m_lt, ties}
                    : Candidate{pairs[i].second, pairs[i].first, m_gt, ties};
    }
  });
  return cand;
}

}  // namespace

LearnedPattern learnBriefPattern(const PatchSamples& s, const PatternLearningOptions& o) {
  const auto& disc = briefDisc();
  const size_t n = s.keypoints();
  checkInput(s, o);
  const std::vector<Candidate> cand = scoreCandidates(s, o);
  std::vector<size_t> order;
  for (size_t i = 0; i < cand.size(); ++i)
    if (cand[i].ties <= o.max_tie_share) order.push_back(i);
  std::stable_sort(order.begin(), order.end(), [&](size_t x, size_t y) {
    return std::abs(cand[x].mean - 0.5) < std::abs(cand[y].mean - 0.5);
  });
  const size_t pool = std::min(o.pool, order.size());

  // Bits of the pool's candidates, packed, filled in blocks as the walk reaches them.
  const size_t words = (n + 63) / 64;
  std::vector<std::vector<uint64_t>> packed(pool);
  size_t filled = 0;
  auto fill = [&](size_t upto) {
    if (upto <= filled) return;
    upto = std::min(pool, std::max(upto, filled + 1024));
    parallelFor(upto - filled, o.threads, [&](size_t j) {
      const Candidate& c = cand[order[filled + j]];
      const uint8_t* va = s.values[c.a].data();
      const uint8_t* vb = s.values[c.b].data();
      std::vector<uint64_t> w(words, 0);
      for (size_t k = 0; k < n; ++k) w[k / 64] |= static_cast<uint64_t>(va[k] < vb[k]) << (k % 64);
      packed[filled + j] = std::move(w);
    });
    filled = upto;
  };
  auto correlation = [&](size_t x, size_t y) {
    const auto &wx = packed[x], &wy = packed[y];
    uint64_t both = 0;
    for (size_t w = 0; w < words; ++w) both += static_cast<uint64_t>(__builtin_popcountll(wx[w] & wy[w]));
    const double px = cand[order[x]].mean, py = cand[order[y]].mean;
    return (double(both) / n - px * py) / std::sqrt(px * (1 - px) * py * (1 - py));
  };

  // 4. The greedy walk, raising the threshold until it keeps `bits` tests.
  LearnedPattern out;
  out.candidates = order.size();
  for (int step = 0;; ++step) {
    const double t = o.start_threshold + step * o.threshold_step;
    if (t > 1 + 1e-9) break;
    std::vector<size_t> kept;
    size_t i = 0;
    for (; i < pool && kept.size() < size_t(o.bits); ++i) {
      const double m = cand[order[i]].mean;
      if (m <= 0 || m >= 1) break;  // constant bits from here on (ordered by balance)
      fill(i + 1);
      bool ok = true;
      for (size_t j = 0; ok && j < kept.size(); ++j) ok = std::abs(correlation(kept[j], i)) < t;
      if (ok) kept.push_back(i);
    }
    if (kept.size() < size_t(o.bits)) continue;
    out.threshold = t;
    out.walked = i;
    double sum = 0, max = 0;
    size_t count = 0;
    for (size_t x = 0; x < kept.size(); ++x) {
      const Candidate& c = cand[order[kept[x]]];
      out.tests.push_back({static_cast<int8_t>(disc[c.a].x), static_cast<int8_t>(disc[c.a].y),
                           static_cast<int8_t>(disc[c.b].x), static_cast<int8_t>(disc[c.b].y)});
      out.mean.push_back(c.mean);
      out.tie_share += c.ties / kept.size();
      for (size_t y = x + 1; y < kept.size(); ++y, ++count) {
        const double r = std::abs(correlation(kept[x], kept[y]));
        sum += r;
        max = std::max(max, r);
      }
    }
    out.mean_abs_correlation = count ? sum / count : 0;
    out.max_abs_correlation = max;
    return out;
  }
  throw FeatureError("the " + std::to_string(pool) + " best-balanced candidates do not give " +
                     std::to_string(o.bits) +
                     " tests at any correlation bound (too few samples or too small a pool)");
}

}  // namespace binloop
