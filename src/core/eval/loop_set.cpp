#include "binloop/eval/loop_set.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "binloop/io/data_error.h"
#include "binloop/io/kitti_sequence.h"
#include "binloop/util/hash_random.h"

namespace fs = std::filesystem;

namespace binloop {

namespace {

const cv::Size kFrame(640, 480);

// A 4:3 window of 70 % of the image width (or the full height when that is the limit), `x_frac` of the
// way from the left edge to the right (0.5: moved by 15 % of the width), vertically centred.
// `span` receives the window's left and right edges as fractions of the image width.
cv::Mat crop(const cv::Mat& img, double x_frac, std::pair<double, double>* span) {
  int w = static_cast<int>(0.7 * img.cols), h = w * 3 / 4;
  if (h > img.rows) h = img.rows, w = h * 4 / 3;
  const int x = static_cast<int>(x_frac * (img.cols - w)), y = (img.rows - h) / 2;
  *span = {double(x) / img.cols, double(x + w) / img.cols};
  cv::Mat out;
  cv::resize(img(cv::Rect(x, y, w, h)), out, kFrame, 0, 0, cv::INTER_AREA);
  return out;
}

// The same scene from elsewhere: a random homography (corners moved by up to 8 % of the size, rotated by
// up to 8 degrees, scaled by 0.85-1.15), other light (gain, offset, gamma), slight blur, sensor noise.
cv::Mat otherView(const cv::Mat& img, HashRng& rng) {
  const float w = static_cast<float>(img.cols), h = static_cast<float>(img.rows);
  const std::vector<cv::Point2f> src{{0, 0}, {w, 0}, {w, h}, {0, h}};
  const double angle = rng.uniform(-8, 8) * CV_PI / 180, scale = rng.uniform(0.85, 1.15);
  std::vector<cv::Point2f> dst;
  for (const auto& p : src) {
    const double dx = p.x - w / 2 + rng.uniform(-0.08, 0.08) * w,
                 dy = p.y - h / 2 + rng.uniform(-0.08, 0.08) * h;
    dst.emplace_back(static_cast<float>(w / 2 + scale * (std::cos(angle) * dx - std::sin(angle) * dy)),
                     static_cast<float>(h / 2 + scale * (std::sin(angle) * dx + std::cos(angle) * dy)));
  }
  cv::Mat warped;
  cv::warpPerspective(img, warped, cv::getPerspectiveTransform(src, dst), img.size(), cv::INTER_LINEAR,
                      cv::BORDER_REFLECT101);
  const double gain = rng.uniform(0.7, 1.3), offset = rng.uniform(-20, 20), gamma = rng.uniform(0.8, 1.25);
  cv::Mat lut(1, 256, CV_8U);
  for (int i = 0; i < 256; ++i)
    lut.at<uint8_t>(i) = cv::saturate_cast<uint8_t>(255.0 * std::pow(i / 255.0, gamma) * gain + offset);
  cv::LUT(warped, lut, warped);
  const double sigma = rng.uniform(0.0, 1.0);
  if (sigma > 0.3) cv::GaussianBlur(warped, warped, cv::Size(0, 0), sigma);
  cv::Mat noise(warped.size(), CV_16S);
  for (int r = 0; r < noise.rows; ++r) {
    for (int c = 0; c < noise.cols; ++c)
      noise.at<int16_t>(r, c) = static_cast<int16_t>(std::lround(rng.uniform(-4, 4)));
  }
  cv::Mat out;
  warped.convertTo(out, CV_16S);
  out += noise;
  out.convertTo(out, CV_8U);
  return out;
}

}  // namespace

std::vector<LoopSetPlace> readLoopSetList(const std::string& path, const std::string& shared_dir) {
  std::ifstream in(path);
  if (!in) throw dataError(path, 0, "cannot open the loop-set list");
  auto expand = [&](std::string p) {
    if (p.rfind("$SHARED", 0) == 0) p = shared_dir + p.substr(7);
    return p;
  };
  std::vector<LoopSetPlace> places;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream ss(line);
    LoopSetPlace p;
    std::string extra;
    if (!(ss >> p.name)) continue;
    if (!(ss >> p.first)) throw dataError(path, n, "expected '<name> <image A> [<image B> | = | -]'");
    ss >> p.second;
    if (ss >> extra) throw dataError(path, n, "unexpected '" + extra + "' after the second image");
    p.first = expand(p.first);
    if (p.second == "-") p.second.clear();
    if (!p.second.empty() && p.second != "=") p.second = expand(p.second);
    for (const auto& img : {p.first, p.second}) {
      if (!img.empty() && img != "=" && !fs::is_regular_file(img))
        throw dataError(path, n, img + ": no such image");
    }
    places.push_back(p);
  }
  if (places.empty()) throw dataError(path, 0, "names no places");
  return places;
}

LoopSet makeLoopSet(const std::vector<LoopSetPlace>& places, const std::string& out_dir, uint64_t seed) {
  fs::create_directories(out_dir);
  LoopSet set;
  std::vector<std::vector<int>> first_frames(places.size());
  std::vector<std::pair<double, double>> span;  // per frame
  std::pair<double, double> last_span;
  auto write = [&](const cv::Mat& img, const LoopSetFrame& f) {
    char name[32];
    std::snprintf(name, sizeof name, "%06zu.png", set.frames.size());
    const std::string path = (fs::path(out_dir) / name).string();
    if (!cv::imwrite(path, img)) throw DataError(path + ": cannot write");
    set.frames.push_back(f);
    span.push_back(last_span);
    return static_cast<int>(set.frames.size()) - 1;
  };
  for (size_t i = 0; i < places.size(); ++i) {
    const cv::Mat a = readGrayImage(places[i].first);
    for (int c = 0; c < 3; ++c) {
      first_frames[i].push_back(
          write(crop(a, 0.5 * c, &last_span),
                {places[i].name, places[i].first + " crop " + std::to_string(c), false}));
    }
  }
  std::vector<size_t> order;
  for (size_t i = 0; i < places.size(); ++i)
    if (!places[i].second.empty()) order.push_back(i);
  HashRng shuffle_rng(hashCombine(seed, 0x5eed));
  for (size_t i = order.size(); i > 1; --i)
    std::swap(order[i - 1], order[shuffle_rng.below(static_cast<int>(i))]);
  for (size_t i : order) {
    HashRng rng(hashCombine(seed, i));
    const bool synthetic = places[i].second == "=";
    const cv::Mat b =
        synthetic ? otherView(readGrayImage(places[i].first), rng) : readGrayImage(places[i].second);
    const std::string src = synthetic ? places[i].first + " warped" : places[i].second;
    for (int c = 0; c < 2; ++c) {
      const int q = write(crop(b, 0.2 + 0.6 * c, &last_span),
                          {places[i].name, src + " crop " + std::to_string(c), true});
      // A loop when the two windows share at least half of their width (of the source image; for a
      // real or warped second view this is approximate, as the view itself moved).
      for (int r : first_frames[i]) {
        const double overlap =
            std::min(span[q].second, span[r].second) - std::max(span[q].first, span[r].first);
        if (overlap >= 0.5 * (span[r].second - span[r].first)) set.loops.emplace_back(q, r);
      }
    }
  }
  return set;
}

}  // namespace binloop
