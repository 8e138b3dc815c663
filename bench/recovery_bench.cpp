// Recovery benchmark: how tracking comes back after frames go missing, at several places of rendered
// route 06 (`render --aperiodic-ground`, kitti04 camera, seed 1). Frames 0..start-1 are mapped, `gap`
// frames are dropped, and the 30 frames after the gap are scored against the ground truth carried into
// the map's frame at frame start-1 (the map's own drift before the gap is not recovery's). Prints a table;
// never pass/fail. Takes about 2 minutes on 2 cores. A lost first frame shows the motion model's error.
//   bench_recovery [--config file.yaml] [--gap N ...]     default: the built-in settings, gaps 10 and 20
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "binloop/io/kitti_sequence.h"
#include "binloop/io/trajectory_io.h"
#include "binloop/pipeline/slam_config.h"
#include "binloop/pipeline/slam_pipeline.h"
#include "binloop/sim/stereo_renderer.h"
#include "binloop/sim/texture_bank.h"
#include "binloop/util/cli_args.h"

using namespace binloop;

namespace {

constexpr int kAfter = 30;  // frames scored after each gap

struct Outcome {
  std::string first_state;
  double first_m = 0, worst10_m = 0, worst30_m = 0;
  int lost = 0;
};

Outcome runGap(const std::vector<StereoFrame>& frames, const std::vector<Pose3>& route, const StereoCamera& cam,
               const SlamConfig& config, int start, int gap) {
  SlamPipeline slam(cam, config.tracker, config.mapper, PipelineMode::kLockStep);
  Pose3 last;
  for (int i = 0; i < start; ++i) last = slam.process(frames[i]).T_w_c;
  const Pose3 drift = last * route[start - 1].inverse();
  Outcome o;
  for (int i = start + gap; i < start + gap + kAfter; ++i) {
    const msg::TrackedFrame tf = slam.process(frames[i]);
    const double off = ((drift * route[i]).translation() - tf.T_w_c.translation()).norm();
    const bool lost = tf.state == msg::TrackingState::kLost;
    if (i == start + gap) o.first_state = msg::toString(tf.state), o.first_m = off;
    if (lost) {
      ++o.lost;
      continue;
    }
    if (i < start + gap + 10) o.worst10_m = std::max(o.worst10_m, off);
    o.worst30_m = std::max(o.worst30_m, off);
  }
  return o;
}

int runBench(const SlamConfig& config, const std::vector<int>& gaps) {
  const std::vector<int> starts = {100, 150, 200, 250, 300, 350};
  const std::string poses = std::string(BINLOOP_SHARED_DATA_DIR) + "/kitti/poses/06.txt";
  if (!std::filesystem::exists(poses)) {
    std::fprintf(stderr, "needs %s\n", poses.c_str());
    return 1;
  }
  const std::vector<Pose3> route = readKittiPoses(poses);
  const StereoCamera cam = kittiCameraByName("kitti04");
  sim::WorldParams wp;
  wp.aperiodic_ground = true;
  const auto world = sim::World::build(route, sim::TextureBank::build(sim::defaultTexturePhotos(), 1), wp, 1);
  sim::StereoRenderer renderer(world, cam, {}, 1);
  const int n = starts.back() + *std::max_element(gaps.begin(), gaps.end()) + kAfter;
  const std::vector<StereoFrame> frames = sim::renderFrames(renderer, route, 0, static_cast<size_t>(n));
  std::printf("Rendered 06 (aperiodic ground): frames 0..start-1 mapped, then `gap` frames missing; errors of "
              "the %d frames after the gap, lost frames left out of the worst.\n\n",
              kAfter);
  std::printf("| start | gap | first frame | its error | worst, 10 frames | worst, %d frames | lost |\n", kAfter);
  std::printf("|---|---|---|---|---|---|---|\n");
  for (int gap : gaps)
    for (int start : starts) {
      const Outcome o = runGap(frames, route, cam, config, start, gap);
      std::printf("| %d | %d | %s | %.2f m | %.2f m | %.2f m | %d |\n", start, gap, o.first_state.c_str(), o.first_m,
                  o.worst10_m, o.worst30_m, o.lost);
      std::fflush(stdout);
    }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CliArgs args("bench_recovery", "bench_recovery [--config file.yaml] [--gap N ...]");
  args.option("config", "SLAM settings (config/kitti.yaml's keys); default: the built-in ones")
      .option("gap", "frames dropped; repeat for several (default: 10 and 20)");
  return runTool("bench_recovery", [&] {
    if (!args.parse(argc, argv)) return 0;
    const SlamConfig config = args.has("config") ? loadSlamConfig(args.str("config")) : SlamConfig{};
    std::vector<int> gaps;
    for (const std::string& g : args.all("gap")) {
      if (g.empty() || g.find_first_not_of("0123456789") != std::string::npos || std::stoi(g) < 1)
        throw CliError("--gap '" + g + "': a whole number of frames, at least 1");
      gaps.push_back(std::stoi(g));
    }
    if (gaps.empty()) gaps = {10, 20};
    return runBench(config, gaps);
  });
}
