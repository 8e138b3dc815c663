#include "binloop/sim/stereo_renderer.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "binloop/io/data_error.h"
#include "binloop/io/kitti_calib.h"
#include "binloop/io/trajectory_io.h"
#include "binloop/util/hash_random.h"

namespace fs = std::filesystem;

namespace binloop::sim {

StereoRenderer::StereoRenderer(const World& world, StereoCamera camera, RenderOptions opt, uint64_t seed)
    : world_(world), camera_(camera), opt_(opt), seed_(seed), view_(opt.max_distance_m) {}

cv::Mat StereoRenderer::finish(const cv::Mat& gray_f, int frame, int eye, double stamp_s) const {
  cv::Mat f = gray_f;
  if (opt_.blur_sigma > 0) cv::GaussianBlur(gray_f, f, cv::Size(0, 0), opt_.blur_sigma);
  if (opt_.exposure_swing > 0) {
    // Slow drift with time (periods of 97 s and 41 s): a place revisited minutes later has another exposure.
    const double gain = 1.0 + opt_.exposure_swing * (0.7 * std::sin(stamp_s * 2 * M_PI / 97.0) +
                                                     0.3 * std::sin(stamp_s * 2 * M_PI / 41.0 + 1.0));
    f = f * gain;
  }
  if (opt_.noise_sigma > 0) {
    // Per-pixel normals cost more than the rendering; a seeded table of them, read from a per-frame offset
    // with an odd stride, is as repeatable and ten times cheaper.
    static const std::vector<float> table = [] {
      std::vector<float> t(1u << 20);
      HashRng rng(0x7AB1Eu);
      for (auto& v : t) v = static_cast<float>(rng.normal());
      return t;
    }();
    const uint64_t mask = table.size() - 1;
    HashRng rng(hashCombine(hashCombine(seed_, 0x9015Eu), static_cast<uint64_t>(frame) * 2 + eye));
    uint64_t idx = rng.next() & mask;
    const uint64_t stride = (rng.next() & 0xFFFF) * 2 + 1;
    const float sigma = static_cast<float>(opt_.noise_sigma);
    cv::Mat noisy = f.clone();
    for (int y = 0; y < noisy.rows; ++y) {
      float* p = noisy.ptr<float>(y);
      for (int x = 0; x < noisy.cols; ++x, idx = (idx + stride) & mask) p[x] += sigma * table[idx];
    }
    f = noisy;
  }
  cv::Mat out;
  f.convertTo(out, CV_8U);  // rounds and saturates
  return out;
}

void StereoRenderer::render(int frame, double stamp_s, const Pose3& T_w_c, cv::Mat* left, cv::Mat* right,
                            cv::Mat* depth_left) {
  view_.render(world_, camera_, T_w_c, &gray_, &depth_);
  *left = finish(gray_, frame, 0, stamp_s);
  if (depth_left) depth_.copyTo(*depth_left);
  Pose3 T_c_r = Pose3::Identity();  // right camera sits baseline along +x of the left
  T_c_r.translation() = Eigen::Vector3d(camera_.baseline_m, 0, 0);
  view_.render(world_, camera_, T_w_c * T_c_r, &gray_, &depth_);
  *right = finish(gray_, frame, 1, stamp_s);
}

std::vector<StereoFrame> renderFrames(StereoRenderer& renderer, const std::vector<Pose3>& route, size_t first,
                                      size_t count) {
  std::vector<StereoFrame> frames;
  for (size_t k = 0; k < count && first + k < route.size(); ++k) {
    const size_t i = first + k;
    StereoFrame f;
    f.index = static_cast<int>(k);
    f.stamp_s = 0.1 * static_cast<double>(k);
    renderer.render(static_cast<int>(i), 0.1 * static_cast<double>(i), route[i], &f.left, &f.right);
    frames.push_back(std::move(f));
  }
  return frames;
}

void renderSequence(StereoRenderer& renderer, const SequenceJob& job,
                    const std::function<void(size_t, size_t)>& progress) {
  if (job.route.empty()) throw std::invalid_argument("renderSequence: empty route");
  if (job.times.size() != job.route.size()) {
    throw std::invalid_argument("renderSequence: " + std::to_string(job.times.size()) + " times for " +
                                std::to_string(job.route.size()) + " poses");
  }
  if (job.step == 0) throw std::invalid_argument("renderSequence: step must be >= 1");
  if (job.start > job.end || job.end >= job.route.size()) {
    throw std::invalid_argument("renderSequence: frames " + std::to_string(job.start) + ".." +
                                std::to_string(job.end) + " are outside the route's 0.." +
                                std::to_string(job.route.size() - 1));
  }
  const fs::path out(job.out_dir);
  fs::create_directories(out / "image_0");
  fs::create_directories(out / "image_1");
  std::vector<Pose3> poses;
  std::vector<double> times;
  std::ofstream src((out / "source_frames.txt").string());
  src << "# route frame of each written frame\n";
  const size_t total = (job.end - job.start) / job.step + 1;
  const std::vector<int> png = {cv::IMWRITE_PNG_COMPRESSION, 1};  // fast; files ~25 % larger than level 3
  cv::Mat left, right;
  size_t k = 0;
  for (size_t i = job.start; i <= job.end; i += job.step, ++k) {
    renderer.render(static_cast<int>(i), job.times[i], job.route[i], &left, &right);
    char name[32];
    std::snprintf(name, sizeof name, "%06zu.png", k);
    if (!cv::imwrite((out / "image_0" / name).string(), left, png) ||
        !cv::imwrite((out / "image_1" / name).string(), right, png))
      throw dataError((out / name).string(), 0, "cannot write image");
    poses.push_back(job.route[i]);
    times.push_back(job.times[i] - job.times[job.start]);
    src << i << "\n";
    if (progress) progress(k + 1, total);
  }
  writeKittiCalib((out / "calib.txt").string(), renderer.camera());
  writeTimes((out / "times.txt").string(), times);
  writeKittiPoses((out / "poses.txt").string(), poses);
}

}  // namespace binloop::sim
