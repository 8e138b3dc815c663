// eval-stereo: stereo matching's disparity error against a render's true depth, per range of disparity: the
// sub-pixel fit's bias (median) and noise (MAD), one table per settings file (docs/tools.md).
#include <cstdio>
#include <iostream>

#include "binloop/eval/disparity_error.h"
#include "binloop/io/trajectory_io.h"
#include "binloop/pipeline/slam_config.h"
#include "binloop/sim/stereo_renderer.h"
#include "binloop/sim/texture_bank.h"
#include "binloop/tracking/frame.h"
#include "binloop/util/cli_args.h"

using namespace binloop;

int main(int argc, char** argv) {
  CliArgs args("eval-stereo",
               "eval-stereo --route <poses.txt> [--config a.yaml [--config b.yaml ...]] [--start N --end N "
               "--step N] [--seed N] [--calib kitti00]");
  args.option("route", "ground-truth poses of the route to render (KITTI format)")
      .option("config",
              "SLAM settings whose stereo matching is measured; repeat to compare (default: built-in)")
      .option("start", "first route frame", "0")
      .option("end", "last route frame, inclusive (default: the last)")
      .option("step", "every step-th frame", "20")
      .option("seed", "world and noise seed, as `render --seed` (7: the benchmark's renders)", "7")
      .option("calib", "camera: kitti00 (00-02), kitti03, kitti04 (04-12)", "kitti00");
  return runTool("eval-stereo", [&] {
    if (!args.parse(argc, argv)) return 0;
    if (!args.has("route")) throw CliError("--route is required");
    const std::vector<Pose3> route = readKittiPoses(args.str("route"));
    if (route.size() < 2) throw CliError("--route needs at least 2 poses");
    const long start = args.integer("start"), step = args.integer("step");
    const long end = args.has("end") ? args.integer("end") : static_cast<long>(route.size()) - 1;
    if (start < 0 || end < start || end >= static_cast<long>(route.size()) || step < 1)
      throw CliError("--start/--end/--step: frames 0-" + std::to_string(route.size() - 1) + ", step >= 1");
    std::vector<std::string> configs = args.all("config");
    if (configs.empty()) configs.push_back("");
    std::vector<SlamConfig> settings;
    for (const std::string& c : configs) settings.push_back(c.empty() ? SlamConfig{} : loadSlamConfig(c));

    const StereoCamera cam = kittiCameraByName(args.str("calib"));
    std::vector<FrameBuilder> builders;
    for (const SlamConfig& c : settings) builders.emplace_back(cam, c.tracker.orb, c.tracker.stereo);
    const auto seed = static_cast<uint64_t>(args.integer("seed"));
    const auto world =
        sim::World::build(route, sim::TextureBank::build(sim::defaultTexturePhotos(), seed), {}, seed);
    sim::StereoRenderer renderer(world, cam, {}, seed);
    std::vector<std::vector<DisparityError>> errors(settings.size());
    long frames = 0;
    for (long i = start; i <= end; i += step, ++frames) {
      StereoFrame in;
      in.index = static_cast<int>(i);
      in.stamp_s = 0.1 * i;
      cv::Mat depth;
      renderer.render(static_cast<int>(i), in.stamp_s, route[static_cast<size_t>(i)], &in.left, &in.right,
                      &depth);
      for (size_t c = 0; c < settings.size(); ++c) {
        const auto e = disparityErrors(builders[c].build(in).keypoints, depth, cam);
        errors[c].insert(errors[c].end(), e.begin(), e.end());
      }
    }
    const std::vector<double> edges = {0, 4, 8, 16, 32, 1e9};
    for (size_t c = 0; c < settings.size(); ++c) {
      std::cout << "eval-stereo: " << (configs[c].empty() ? "built-in settings" : configs[c]) << ", "
                << frames << " frames, "
                << (settings[c].tracker.stereo.fit == StereoMatchParams::SubPixelFit::kEquiangular
                        ? "equiangular"
                        : "parabola")
                << " fit\n";
      std::printf("  %-18s %7s %10s %8s %8s\n", "true disparity px", "n", "median px", "MAD px", "wrong");
      for (const DisparityErrorSummary& s : summariseDisparityErrors(errors[c], edges)) {
        const std::string range = s.hi > 1e8 ? std::to_string(static_cast<int>(s.lo)) + "+"
                                             : std::to_string(static_cast<int>(s.lo)) + "-" +
                                                   std::to_string(static_cast<int>(s.hi));
        std::printf("  %-18s %7zu %+10.4f %8.4f %7.1f%%\n", range.c_str(), s.n, s.median, s.mad,
                    100 * s.wrong);
      }
    }
    return 0;
  });
}
