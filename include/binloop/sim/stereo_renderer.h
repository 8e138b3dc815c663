#pragma once
// Renders rectified stereo pairs of a World and writes whole sequences in KITTI layout.
#include <functional>
#include <string>
#include <vector>

#include "binloop/io/kitti_sequence.h"
#include "binloop/sim/view_renderer.h"
#include "binloop/sim/world.h"

namespace binloop::sim {

struct RenderOptions {
  double blur_sigma = 0.6;      // optics: a slight blur, as real lenses give (0 = off)
  double noise_sigma = 2.0;     // sensor noise, grey levels (0 = off); seeded per frame, so still repeatable
  double exposure_swing = 0.0;  // gain varies by ±this over time, so revisits differ in exposure (0 = off)
  double max_distance_m = 180.0;
};

class StereoRenderer {
 public:
  StereoRenderer(const World& world, StereoCamera camera, RenderOptions opt, uint64_t seed);
  /// Left and right 8-bit images of frame `frame` (for seeding noise) at time `stamp_s` with left pose T_w_c.
  /// `depth_left` (optional) receives the left camera's z-depth in metres (+inf for sky).
  void render(int frame, double stamp_s, const Pose3& T_w_c, cv::Mat* left, cv::Mat* right,
              cv::Mat* depth_left = nullptr);
  const StereoCamera& camera() const { return camera_; }

 private:
  cv::Mat finish(const cv::Mat& gray_f, int frame, int eye, double stamp_s) const;
  const World& world_;
  StereoCamera camera_;
  RenderOptions opt_;
  uint64_t seed_;
  ViewRenderer view_;
  cv::Mat gray_, depth_;
};

/// Route poses first .. first+count-1 as in-memory frames for the SLAM: numbered from 0 at 10 Hz (index k,
/// stamp 0.1 k s), each rendered as route frame first+k (its noise seeded by that number), so they are the
/// images `render` writes for those frames. Stops early at the route's end.
std::vector<StereoFrame> renderFrames(StereoRenderer& renderer, const std::vector<Pose3>& route, size_t first,
                                      size_t count);

struct SequenceJob {
  std::vector<Pose3> route;   // ground truth of the whole route (the world is built around all of it)
  std::vector<double> times;  // one per route pose
  size_t start = 0, end = 0, step = 1;  // frames start..end (inclusive), every `step`
  std::string out_dir;
};

/// Writes image_0/, image_1/, calib.txt, times.txt, poses.txt and source_frames.txt (the route frame of
/// each written frame) to job.out_dir. `progress(done, total)` is called after every frame.
void renderSequence(StereoRenderer& renderer, const SequenceJob& job,
                    const std::function<void(size_t, size_t)>& progress = {});

}  // namespace binloop::sim
