// Renderer benchmark: frames per second on one core at KITTI size (median of 5 runs), and how ORB
// features on rendered frames compare with the real KITTI 00 sample (count, spread, frame-to-frame and
// left-right match rates). Prints tables; never pass/fail.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <opencv2/core/utility.hpp>
#include <opencv2/features2d.hpp>

#include "bench_stats.h"
#include "binloop/io/kitti_sequence.h"
#include "binloop/io/trajectory_io.h"
#include "binloop/sim/stereo_renderer.h"

using namespace binloop;

namespace {

struct OrbStats {
  double keypoints = 0, spread = 0, temporal = 0, stereo = 0;
};

using binloop::bench::median;

// Averages over consecutive stereo frames: ORB (2000, 8 levels) count; share of 16x6 grid cells with a
// keypoint; share of keypoints with a ratio-test match in the next left frame; share with a ratio-test
// match in the right image on the same row (|dy| <= 2, disparity 0..200).
OrbStats orbStats(const std::vector<std::pair<cv::Mat, cv::Mat>>& frames) {
  auto orb = cv::ORB::create(2000);
  cv::BFMatcher bf(cv::NORM_HAMMING);
  OrbStats s;
  std::vector<cv::KeyPoint> prev_kp;
  cv::Mat prev_desc;
  for (size_t i = 0; i < frames.size(); ++i) {
    std::vector<cv::KeyPoint> kl, kr;
    cv::Mat dl, dr;
    orb->detectAndCompute(frames[i].first, cv::noArray(), kl, dl);
    orb->detectAndCompute(frames[i].second, cv::noArray(), kr, dr);
    s.keypoints += kl.size();
    std::vector<int> cells(96, 0);
    for (const auto& k : kl)
      cells[std::min(5, static_cast<int>(k.pt.y * 6 / frames[i].first.rows)) * 16 +
            std::min(15, static_cast<int>(k.pt.x * 16 / frames[i].first.cols))] = 1;
    s.spread += std::count(cells.begin(), cells.end(), 1) / 96.0;
    std::vector<std::vector<cv::DMatch>> knn;
    bf.knnMatch(dl, dr, knn, 2);
    int st = 0;
    for (const auto& m : knn)
      if (m.size() == 2 && m[0].distance < 0.8f * m[1].distance) {
        const auto& a = kl[m[0].queryIdx].pt;
        const auto& b = kr[m[0].trainIdx].pt;
        if (std::abs(a.y - b.y) <= 2 && a.x - b.x >= 0 && a.x - b.x < 200) ++st;
      }
    s.stereo += kl.empty() ? 0 : static_cast<double>(st) / kl.size();
    if (i > 0) {
      bf.knnMatch(prev_desc, dl, knn, 2);
      int tm = 0;
      for (const auto& m : knn)
        if (m.size() == 2 && m[0].distance < 0.8f * m[1].distance) ++tm;
      s.temporal += prev_kp.empty() ? 0 : static_cast<double>(tm) / prev_kp.size();
    }
    prev_kp = kl;
    prev_desc = dl;
  }
  const double n = static_cast<double>(frames.size());
  s.keypoints /= n;
  s.spread /= n;
  s.stereo /= n;
  s.temporal /= std::max(1.0, n - 1);
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  cv::setNumThreads(1);  // one core, as the goal is stated
  const std::string shared = argc > 1 ? argv[1] : std::string(BINLOOP_SHARED_DATA_DIR);
  const auto route = readKittiPoses(shared + "/kitti/poses/00.txt");
  const auto world = sim::World::build(route, sim::TextureBank::build(sim::defaultTexturePhotos(), 1), {}, 1);
  sim::StereoRenderer renderer(world, kitti00Camera(), {}, 1);

  // Speed: 40 frames spread over route 00, 5 runs.
  std::vector<double> fps;
  cv::Mat l, r;
  for (int run = 0; run < 5; ++run) {
    const auto t0 = std::chrono::steady_clock::now();
    int n = 0;
    for (size_t i = 0; i < route.size(); i += route.size() / 40, ++n)
      renderer.render(static_cast<int>(i), 0.1 * i, route[i], &l, &r);
    fps.push_back(n / std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  std::printf("\nrender speed, 1241x376 stereo, one thread, 40 frames of route 00, 5 runs\n");
  std::printf("| median frames/s | min | max | whole route 00 (4541 frames) |\n|---|---|---|---|\n");
  std::printf("| %.1f | %.1f | %.1f | %.1f min |\n", median(fps), *std::min_element(fps.begin(), fps.end()),
              *std::max_element(fps.begin(), fps.end()), 4541 / median(fps) / 60);

  // ORB statistics: real sample_00 frames 0-10 against the rendered frames 0-10 of route 00.
  std::vector<std::pair<cv::Mat, cv::Mat>> real, rendered;
  try {
    const auto seq = KittiSequence::open(shared + "/kitti/sample_00");
    for (size_t i = 0; i < seq.size(); ++i) {
      auto f = seq.load(i);
      real.emplace_back(f.left, f.right);
    }
  } catch (const std::exception& e) {
    std::printf("(no real sample: %s)\n", e.what());
  }
  for (int i = 0; i <= 10; ++i) {
    renderer.render(i, 0.1 * i, route[i], &l, &r);
    rendered.emplace_back(l.clone(), r.clone());
  }
  std::printf("\nORB (2000 features) on KITTI 00 frames 0-10: real vs rendered along the same route\n");
  std::printf(
      "| images | keypoints | grid cells covered (16x6) | matched in next frame | matched in right image "
      "|\n");
  std::printf("|---|---|---|---|---|\n");
  auto row = [](const char* name, const OrbStats& s) {
    std::printf("| %s | %.0f | %.0f %% | %.0f %% | %.0f %% |\n", name, s.keypoints, 100 * s.spread,
                100 * s.temporal, 100 * s.stereo);
  };
  if (!real.empty()) row("real KITTI 00 sample", orbStats(real));
  row("rendered route 00 (defaults)", orbStats(rendered));
  for (double noise : {2.0, 4.0}) {
    sim::RenderOptions opt;
    opt.noise_sigma = noise;
    sim::StereoRenderer noisy(world, kitti00Camera(), opt, 1);
    rendered.clear();
    for (int i = 0; i <= 10; ++i) {
      noisy.render(i, 0.1 * i, route[i], &l, &r);
      rendered.emplace_back(l.clone(), r.clone());
    }
    const std::string name = "rendered route 00, --noise " + std::to_string(static_cast<int>(noise));
    row(name.c_str(), orbStats(rendered));
  }
  return 0;
}
