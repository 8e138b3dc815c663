#include "binloop/features/orb_slam_extractor.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <numeric>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "binloop/features/feature_error.h"
#include "binloop/util/hash_random.h"

namespace binloop {

namespace {

constexpr int kPatchSize = 31;
constexpr int kHalfPatch = 15;
// FAST sees cells within [kEdge - 3, size - kEdge + 3) and skips 3 pixels inside whatever it is given, so
// corners land at least kEdge from the border: the orientation disc and the rotated pattern (radius 15)
// then never read outside the level.
constexpr int kEdge = 19;

constexpr uint64_t kPatternSeed = 0x62696e6c6f6f70ull;  // "binloop"; changing it changes every descriptor

cv::Point gaussianPoint(HashRng& rng) {
  const double sigma = kPatchSize / 5.0;
  for (;;) {
    const cv::Point q(static_cast<int>(std::lround(sigma * rng.normal())),
                      static_cast<int>(std::lround(sigma * rng.normal())));
    if (q.dot(q) <= kHalfPatch * kHalfPatch) return q;
  }
}

// Half-widths of the orientation disc per row: pixel centres within radius 15.5. The test is symmetric in
// u and v, so the disc is too, and the centroid has no bias towards either axis.
const std::array<int, kHalfPatch + 1>& discHalfWidths() {
  static const std::array<int, kHalfPatch + 1> umax = [] {
    std::array<int, kHalfPatch + 1> u{};
    const double r2 = (kHalfPatch + 0.5) * (kHalfPatch + 0.5);
    for (int v = 0; v <= kHalfPatch; ++v) u[v] = static_cast<int>(std::floor(std::sqrt(r2 - v * v)));
    return u;
  }();
  return umax;
}

// Intensity centroid (Rosin): the angle from the corner to the centre of mass of its disc, in degrees.
// Rows v and -v are visited together, so m_01 needs one difference per pixel pair.
float centroidAngle(const cv::Mat& img, cv::Point pt) {
  const auto& umax = discHalfWidths();
  const uint8_t* c = img.ptr<uint8_t>(pt.y) + pt.x;
  const int step = static_cast<int>(img.step1());
  int m01 = 0, m10 = 0;
  for (int u = -kHalfPatch; u <= kHalfPatch; ++u) m10 += u * c[u];
  for (int v = 1; v <= kHalfPatch; ++v) {
    int diff = 0;
    for (int u = -umax[v]; u <= umax[v]; ++u) {
      const int below = c[u + v * step], above = c[u - v * step];
      diff += below - above;
      m10 += u * (below + above);
    }
    m01 += v * diff;
  }
  return cv::fastAtan2(static_cast<float>(m01), static_cast<float>(m10));
}

// The pattern's points as float columns, so rotating all 512 is one tight loop.
struct PatternXY {
  std::array<float, 2 * size_t{Desc256::kBits}> x, y;
};

const PatternXY& patternXY() {
  static const PatternXY xy = [] {
    PatternXY t;
    const BriefPattern& p = briefPattern();
    for (size_t b = 0; b < p.size(); ++b) {
      t.x[2 * b] = p[b].ax;
      t.y[2 * b] = p[b].ay;
      t.x[2 * b + 1] = p[b].bx;
      t.y[2 * b + 1] = p[b].by;
    }
    return t;
  }();
  return xy;
}

Desc256 rotatedBrief(const cv::Mat& blurred, const cv::KeyPoint& kp) {
  const PatternXY& pat = patternXY();
  float cs, sn;
  briefRotation(kp.angle, &cs, &sn);
  const uint8_t* c = blurred.ptr<uint8_t>(cvRound(kp.pt.y)) + cvRound(kp.pt.x);
  const int step = static_cast<int>(blurred.step1());
  std::array<int, 2 * size_t{Desc256::kBits}> offset;
  for (size_t i = 0; i < offset.size(); ++i) {
    const cv::Point q = rotatedTestPoint(pat.x[i], pat.y[i], cs, sn);
    offset[i] = q.y * step + q.x;
  }
  Desc256 d;
  for (int w = 0; w < 4; ++w) {
    uint64_t bits = 0;
    for (int b = 0; b < 64; ++b) {
      const int i = 2 * (64 * w + b);
      bits |= static_cast<uint64_t>(c[offset[i]] < c[offset[i + 1]]) << b;
    }
    d.w[w] = bits;
  }
  return d;
}

// FAST in a grid of cells with a fallback threshold: a cell that has no corner at ini_fast is searched again
// at min_fast, so low-contrast regions (road, sky, shadow) still offer corners to the quadtree. The
// ini_fast pass runs once over the whole level and its corners are then binned by cell. ORB-SLAM2 calls
// FAST once per cell (1220 calls per KITTI frame): 8.9 ms here, against 4.2 ms this way. The corners are
// the same except at cell edges, where one pass also suppresses non-maxima across the edge. A fallback
// cell is seen with a 3-pixel margin, since FAST skips 3 pixels inside whatever it is given, so it tests
// exactly the cell's own pixels.
std::vector<cv::KeyPoint> fastInCells(const cv::Mat& img, const OrbSlamParams& p, cv::Rect* area) {
  const int lo = kEdge - 3, hi_x = img.cols - kEdge + 3, hi_y = img.rows - kEdge + 3;
  *area = cv::Rect(lo, lo, std::max(0, hi_x - lo), std::max(0, hi_y - lo));
  std::vector<cv::KeyPoint> all, cell;
  if (area->width <= 6 || area->height <= 6) return all;
  cv::FAST(img(*area), all, p.ini_fast, true);
  const int cols = std::max(1, area->width / p.cell_px), rows = std::max(1, area->height / p.cell_px);
  const int cw = (area->width + cols - 1) / cols, ch = (area->height + rows - 1) / rows;
  std::vector<char> found(static_cast<size_t>(rows * cols), 0);
  for (auto& k : all) {  // corners are at >= 3 inside the area; cell c's detection band starts at c*cw + 3
    const int c = std::min(cols - 1, (static_cast<int>(k.pt.x) - 3) / cw);
    const int r = std::min(rows - 1, (static_cast<int>(k.pt.y) - 3) / ch);
    found[static_cast<size_t>(r) * cols + c] = 1;
    k.pt.x += static_cast<float>(lo);
    k.pt.y += static_cast<float>(lo);
  }
  if (p.min_fast >= p.ini_fast) return all;
  for (int r = 0; r < rows; ++r) {
    const int y0 = lo + r * ch, y1 = std::min(y0 + ch + 6, hi_y);
    if (y1 - y0 <= 6) continue;
    for (int c = 0; c < cols; ++c) {
      const int x0 = lo + c * cw, x1 = std::min(x0 + cw + 6, hi_x);
      if (x1 - x0 <= 6 || found[static_cast<size_t>(r) * cols + c]) continue;
      cv::FAST(img(cv::Range(y0, y1), cv::Range(x0, x1)), cell, p.min_fast, true);
      for (auto& k : cell) {
        k.pt.x += static_cast<float>(x0);
        k.pt.y += static_cast<float>(y0);
        all.push_back(k);
      }
    }
  }
  return all;
}

bool stronger(const cv::KeyPoint& a, const cv::KeyPoint& b) {
  if (a.response != b.response) return a.response > b.response;
  return a.pt.y != b.pt.y ? a.pt.y < b.pt.y : a.pt.x < b.pt.x;
}

// A quadtree node: a box and its keypoints, a range of `idx`.
struct Node {
  float x0, y0, x1, y1;
  int begin, end;
  int count() const { return end - begin; }
  // FAST corners sit on integer pixels, so a box under a pixel wide and high holds a single position.
  bool splittable() const { return count() > 1 && (x1 - x0 >= 1.f || y1 - y0 >= 1.f); }
};

class QuadTree {
 public:
  QuadTree(const std::vector<cv::KeyPoint>& kps, cv::Rect area) : kps_(kps), idx_(kps.size()) {
    std::iota(idx_.begin(), idx_.end(), 0);
    // Square-ish roots side by side, so that a wide image is cut into squares and not into slivers.
    const int roots =
        std::max(1, static_cast<int>(std::lround(static_cast<double>(area.width) / area.height)));
    const float rw = static_cast<float>(area.width) / roots;
    auto root = [&](int i) { return std::min(roots - 1, static_cast<int>((kps_[i].pt.x - area.x) / rw)); };
    for (int b = 0, r = 0; r < roots; ++r) {
      const int e = static_cast<int>(
          std::partition(idx_.begin() + b, idx_.end(), [&](int i) { return root(i) == r; }) - idx_.begin());
      if (e > b) {
        nodes_.push_back({area.x + r * rw, static_cast<float>(area.y), area.x + (r + 1) * rw,
                          static_cast<float>(area.y + area.height), b, e});
      }
      b = e;
    }
  }

  // Splits until there are `target` nodes or no node can be split. Whole rounds while a round cannot
  // overshoot (a split adds at most 3 nodes); then the most crowded nodes first, so the count stops at the
  // target (at most 2 above it) and the last splits go where corners are densest.
  void splitTo(int target) {
    while (static_cast<int>(nodes_.size()) < target) {
      std::vector<int> order;
      for (int i = 0; i < static_cast<int>(nodes_.size()); ++i)
        if (nodes_[i].splittable()) order.push_back(i);
      if (order.empty()) return;
      const bool whole_round = static_cast<int>(nodes_.size() + 3 * order.size()) <= target;
      if (!whole_round) {
        std::stable_sort(order.begin(), order.end(),
                         [&](int a, int b) { return nodes_[a].count() > nodes_[b].count(); });
      }
      std::vector<Node> next;
      std::vector<char> replaced(nodes_.size(), 0);
      int total = static_cast<int>(nodes_.size());
      for (int i : order) {
        if (!whole_round && total >= target) break;
        const size_t before = next.size();
        split(nodes_[i], &next);
        total += static_cast<int>(next.size() - before) - 1;
        replaced[i] = 1;
      }
      for (size_t i = 0; i < nodes_.size(); ++i)
        if (!replaced[i]) next.push_back(nodes_[i]);
      nodes_.swap(next);
    }
  }

  std::vector<cv::KeyPoint> strongestPerNode() const {
    std::vector<cv::KeyPoint> out;
    out.reserve(nodes_.size());
    for (const Node& n : nodes_) {
      int best = idx_[n.begin];
      for (int k = n.begin + 1; k < n.end; ++k)
        if (stronger(kps_[idx_[k]], kps_[best])) best = idx_[k];
      out.push_back(kps_[best]);
    }
    std::sort(out.begin(), out.end(), [](const cv::KeyPoint& a, const cv::KeyPoint& b) {
      return a.pt.y != b.pt.y ? a.pt.y < b.pt.y : a.pt.x < b.pt.x;
    });
    return out;
  }

 private:
  void split(const Node& n, std::vector<Node>* out) {
    const float mx = 0.5f * (n.x0 + n.x1), my = 0.5f * (n.y0 + n.y1);
    const auto first = idx_.begin();
    const auto top = std::partition(first + n.begin, first + n.end, [&](int i) { return kps_[i].pt.y < my; });
    const auto tl = std::partition(first + n.begin, top, [&](int i) { return kps_[i].pt.x < mx; });
    const auto bl = std::partition(top, first + n.end, [&](int i) { return kps_[i].pt.x < mx; });
    const int t = static_cast<int>(top - first), l = static_cast<int>(tl - first),
              b = static_cast<int>(bl - first);
    const Node kids[4] = {{n.x0, n.y0, mx, my, n.begin, l},
                          {mx, n.y0, n.x1, my, l, t},
                          {n.x0, my, mx, n.y1, t, b},
                          {mx, my, n.x1, n.y1, b, n.end}};
    for (const Node& k : kids)
      if (k.count() > 0) out->push_back(k);
  }

  const std::vector<cv::KeyPoint>& kps_;
  std::vector<int> idx_;
  std::vector<Node> nodes_;
};

void checkImage(const cv::Mat& gray) {
  if (gray.empty()) throw FeatureError("cannot extract ORB features from an empty image");
  if (gray.type() != CV_8UC1) {
    throw FeatureError("ORB needs an 8-bit single-channel (grey) image, got " +
                       cv::typeToString(gray.type()));
  }
}

// OpenCV's ORB describes keypoints it is handed without moving them: on a single level (octave 0) it pads
// the level by reflection, smooths it as briefSmoothed() does and reads its learned pattern at each
// keypoint's own angle. Edge threshold 0 keeps every keypoint (ours stay kEdge from the border, and the
// padding covers the rotated pattern). A fresh instance per call: ORB keeps no state, but nothing promises
// that one instance may serve several threads.
void describeWithOrb(const cv::Mat& level, std::vector<cv::KeyPoint>& kps, Descriptors& out) {
  if (kps.empty()) return;
  const cv::Ptr<cv::ORB> orb =
      cv::ORB::create(static_cast<int>(kps.size()), 1.2f, 1, /*edgeThreshold=*/0,
                      /*firstLevel=*/0, /*WTA_K=*/2, cv::ORB::FAST_SCORE, kPatchSize);
  std::vector<cv::KeyPoint> level_kps = kps;
  for (auto& k : level_kps) k.octave = 0;
  cv::Mat desc;
  orb->compute(level, level_kps, desc);
  if (level_kps.size() != kps.size() || desc.rows != static_cast<int>(kps.size()) || desc.cols != 32 ||
      desc.type() != CV_8UC1) {
    throw FeatureError("ORB-SLAM extractor: OpenCV's ORB described " + std::to_string(desc.rows) + " of " +
                       std::to_string(kps.size()) + " keypoints");
  }
  for (int r = 0; r < desc.rows; ++r) {
    Desc256 d;
    std::memcpy(d.w.data(), desc.ptr<uint8_t>(r), 32);  // test 8j+i is bit i of byte j, as OpenCV matches it
    out.push_back(d);
  }
}

[[noreturn]] void fail(const std::string& what) { throw FeatureError("ORB-SLAM extractor: " + what); }

// Messages are built only on failure: extract() checks its pyramid on every frame.
void require(bool ok, const std::string& what) {
  if (!ok) fail(what);
}

}  // namespace

// Drawn once; a repeated or degenerate pair would waste a bit on a constant or a copy.
const BriefPattern& briefPattern() {
  static const BriefPattern pattern = [] {
    BriefPattern p;
    HashRng rng(kPatternSeed);
    for (int b = 0; b < Desc256::kBits;) {
      const cv::Point a = gaussianPoint(rng), c = gaussianPoint(rng);
      bool fresh = a != c;
      for (int k = 0; fresh && k < b; ++k) {
        const cv::Point pa(p[k].ax, p[k].ay), pc(p[k].bx, p[k].by);
        fresh = !((pa == a && pc == c) || (pa == c && pc == a));
      }
      if (!fresh) continue;
      p[b] = {static_cast<int8_t>(a.x), static_cast<int8_t>(a.y), static_cast<int8_t>(c.x),
              static_cast<int8_t>(c.y)};
      ++b;
    }
    return p;
  }();
  return pattern;
}

void briefSmoothed(const cv::Mat& level, cv::Mat& out) {
  cv::GaussianBlur(level, out, cv::Size(7, 7), 2, 2, cv::BORDER_REFLECT_101);
}

const char* briefPatternName(BriefPatternKind k) {
  return k == BriefPatternKind::kGaussian ? "gaussian" : "orb";
}

BriefPatternKind briefPatternFromName(const std::string& name) {
  if (name == "orb") return BriefPatternKind::kOrbLearned;
  if (name == "gaussian") return BriefPatternKind::kGaussian;
  throw FeatureError("unknown BRIEF pattern '" + name + "' (known: orb, gaussian)");
}

bool OrbSlamParams::operator==(const OrbSlamParams& o) const {
  return features == o.features && scale_factor == o.scale_factor && levels == o.levels &&
         ini_fast == o.ini_fast && min_fast == o.min_fast && cell_px == o.cell_px && pattern == o.pattern;
}

ExtractorSettings extractorSettings(const OrbSlamParams& p, int max_side) {
  ExtractorSettings e;
  e.kind = p.pattern == BriefPatternKind::kGaussian ? ExtractorKind::kBinloopOrb
                                                    : ExtractorKind::kBinloopOrbRbrief;
  e.features = static_cast<uint32_t>(std::max(0, p.features));
  e.scale_factor = p.scale_factor;
  e.levels = static_cast<uint32_t>(std::max(0, p.levels));
  e.ini_fast = static_cast<uint32_t>(std::max(0, p.ini_fast));
  e.min_fast = static_cast<uint32_t>(std::max(0, p.min_fast));
  e.cell_px = static_cast<uint32_t>(std::max(0, p.cell_px));
  e.max_side = static_cast<uint32_t>(std::max(0, max_side));
  return e;
}

ImagePyramid buildPyramid(const cv::Mat& gray, int levels, float scale_factor) {
  checkImage(gray);
  require(levels >= 1, "levels must be >= 1, got " + std::to_string(levels));
  require(scale_factor > 1.f, "scale_factor must be > 1, got " + std::to_string(scale_factor));
  ImagePyramid pyr;
  pyr.levels.push_back(gray);
  pyr.scale.push_back(1.f);
  for (int i = 1; i < levels; ++i) {
    const float s = std::pow(scale_factor, static_cast<float>(i));
    const cv::Size size(std::max(1, cvRound(gray.cols / s)), std::max(1, cvRound(gray.rows / s)));
    cv::Mat level;
    cv::resize(pyr.levels.back(), level, size, 0, 0, cv::INTER_LINEAR);
    pyr.levels.push_back(level);
    pyr.scale.push_back(s);
  }
  return pyr;
}

OrbSlamExtractor::OrbSlamExtractor(const OrbSlamParams& p) : p_(p) {
  require(p.features >= 1, "features must be >= 1, got " + std::to_string(p.features));
  require(p.levels >= 1, "levels must be >= 1, got " + std::to_string(p.levels));
  require(p.scale_factor > 1.f, "scale_factor must be > 1, got " + std::to_string(p.scale_factor));
  require(p.min_fast >= 1 && p.min_fast <= p.ini_fast,
          "FAST thresholds need 1 <= min_fast <= ini_fast, got " + std::to_string(p.min_fast) + " and " +
              std::to_string(p.ini_fast));
  require(p.cell_px >= 8, "cell_px must be >= 8, got " + std::to_string(p.cell_px));
  const double ratio = 1.0 / p.scale_factor;
  double n = p.features * (1 - ratio) / (1 - std::pow(ratio, p.levels));
  int sum = 0;
  for (int i = 0; i + 1 < p.levels; ++i, n *= ratio) {
    per_level_.push_back(static_cast<int>(std::lround(n)));
    sum += per_level_.back();
  }
  per_level_.push_back(std::max(0, p.features - sum));
}

OrbFeatures OrbSlamExtractor::extract(const cv::Mat& gray) const { return extract(pyramid(gray)); }

OrbFeatures OrbSlamExtractor::extract(const ImagePyramid& pyr) const {
  if (static_cast<int>(pyr.levels.size()) != p_.levels || pyr.scale.size() != pyr.levels.size()) {
    fail("pyramid has " + std::to_string(pyr.levels.size()) + " levels, expected " +
         std::to_string(p_.levels));
  }
  checkImage(pyr.levels[0]);
  for (int i = 0; i < p_.levels; ++i) {
    if (std::abs(pyr.scale[i] - std::pow(p_.scale_factor, static_cast<float>(i))) > 1e-3f * pyr.scale[i]) {
      fail("pyramid level " + std::to_string(i) + " has scale " + std::to_string(pyr.scale[i]) +
           ", not scale_factor^" + std::to_string(i));
    }
    if (pyr.levels[i].type() != CV_8UC1 || pyr.levels[i].cols > pyr.levels[0].cols ||
        pyr.levels[i].rows > pyr.levels[0].rows)
      fail("pyramid level " + std::to_string(i) + " is not 8-bit grey or is larger than level 0");
  }
  OrbFeatures out;
  out.keypoints.reserve(static_cast<size_t>(p_.features) + 8 * static_cast<size_t>(p_.levels));
  out.descriptors.reserve(out.keypoints.capacity());
  // One buffer for every level's blur: a fresh allocation per level cost page faults on each frame.
  cv::Mat blur_buffer;
  if (p_.pattern == BriefPatternKind::kGaussian) blur_buffer.create(pyr.levels[0].size(), CV_8UC1);
  for (int level = 0; level < p_.levels; ++level) {
    const cv::Mat& img = pyr.levels[level];
    cv::Rect area;
    const std::vector<cv::KeyPoint> candidates = fastInCells(img, p_, &area);
    if (candidates.empty() || per_level_[level] == 0) continue;
    QuadTree tree(candidates, area);
    tree.splitTo(per_level_[level]);
    std::vector<cv::KeyPoint> kps = tree.strongestPerNode();
    const float scale = pyr.scale[level];
    for (auto& k : kps) {
      k.size = kPatchSize * scale;
      k.angle = centroidAngle(img, cv::Point(cvRound(k.pt.x), cvRound(k.pt.y)));
    }
    if (p_.pattern == BriefPatternKind::kOrbLearned) {
      describeWithOrb(img, kps, out.descriptors);
    } else {
      // BRIEF compares single pixels, so it reads a smoothed level; the angle uses the raw one as ORB-SLAM2.
      cv::Mat blurred = blur_buffer(cv::Rect(0, 0, img.cols, img.rows));
      briefSmoothed(img, blurred);
      for (const auto& k : kps) out.descriptors.push_back(rotatedBrief(blurred, k));
    }
    for (auto& k : kps) {
      k.octave = level;
      // ORB-SLAM2's mapping. Bilinear resizing puts level pixel x at level-0 (x + 0.5) * r - 0.5 (1.3-2.5 px
      // away at level 7); that exact place was tried and recovery after missing frames lost by it, with no
      // gain in accuracy (docs/decisions.md, 2026-11-30).
      k.pt *= scale;
      out.keypoints.push_back(k);
    }
  }
  return out;
}

}  // namespace binloop
