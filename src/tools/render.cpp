// render: synthetic stereo sequences in KITTI layout along a real ground-truth route (see docs/tools.md).
#include <chrono>
#include <filesystem>
#include <iostream>

#include "binloop/io/filesystem.h"
#include "binloop/io/trajectory_io.h"
#include "binloop/sim/builtin_route.h"
#include "binloop/sim/level_revisits.h"
#include "binloop/sim/stereo_renderer.h"
#include "binloop/util/cli_args.h"
#include "binloop/util/progress_bar.h"

int main(int argc, char** argv) {
  binloop::CliArgs args("render", "render --route <poses.txt> --out <sequence_dir> [options]");
  args.option("route",
              "ground-truth poses of the route (KITTI format, T_w_c per frame), or 'loop' for the built-in "
              "1.3 laps of a 120x200 m block")
      .option("times", "times.txt of the route (default: 10 Hz)")
      .option("out", "sequence folder to write (image_0/, image_1/, calib.txt, times.txt, poses.txt)")
      .option("start", "first route frame", "0")
      .option("end", "last route frame, inclusive (default: the last)")
      .option("step", "render every step-th frame", "1")
      .option("width", "image width (default: the camera's)")
      .option("height", "image height (default: the camera's)")
      .option("calib", "camera: kitti00 (00-02), kitti03, kitti04 (04-12)", "kitti00")
      .option("baseline", "stereo baseline in metres (default: the camera's, 0.537 for kitti00)")
      .option("seed", "world and noise seed: same seed, same bytes", "1")
      .option("noise", "sensor noise sigma in grey levels (seeded: same seed, same noise)", "2")
      .option("lighting", "exposure swing over time, e.g. 0.3 for +-30 % (0 = constant)", "0")
      .option("blur", "optical blur sigma in pixels", "0.6")
      .option("textures", "extra folder of photos for façade textures (added to the Debian photos)")
      .flag("procedural", "use procedural textures only (no photos)")
      .flag("level-revisits",
            "give revisits the height of the earlier pass (ground truth that disagrees in height between "
            "passes, e.g. KITTI 02)")
      .flag("aperiodic-ground",
            "a road texture that never repeats (by default it repeats every 8 m, as every render measured "
            "before it)")
      .flag("rigid-ground",
            "one road surface for the whole world (by default a plane under each camera that follows it, as "
            "in every render measured before it)")
      .flag("force", "write into an existing non-empty folder");
  return binloop::runTool("render", [&] {
    if (!args.parse(argc, argv)) return 0;
    if (!args.has("route") || !args.has("out")) throw binloop::CliError("--route and --out are required");
    auto route =
        args.str("route") == "loop" ? binloop::sim::loopRoute() : binloop::readKittiPoses(args.str("route"));
    if (route.size() < 2) throw binloop::CliError("--route needs at least 2 poses");
    if (args.has("level-revisits")) {
      binloop::sim::LevelResult level = binloop::sim::levelRevisits(route);
      std::cout << "render: levelled " << level.revisit_frames
                << " revisiting frames to the height of the earlier pass, "
                << "heights changed by up to " << level.max_shift_m
                << " m (poses.txt has the levelled route)\n";
      route = std::move(level.route);
    }
    std::vector<double> times;
    if (args.has("times")) {
      times = binloop::readTimes(args.str("times"));
      if (times.size() != route.size())
        throw binloop::CliError("--times has " + std::to_string(times.size()) + " lines but --route has " +
                                std::to_string(route.size()) + " poses");
    } else {
      for (size_t i = 0; i < route.size(); ++i) times.push_back(0.1 * i);
    }
    auto cam = binloop::kittiCameraByName(args.str("calib"));
    if (args.has("width")) cam.width = static_cast<int>(args.integer("width"));
    if (args.has("height")) cam.height = static_cast<int>(args.integer("height"));
    if (args.has("width") || args.has("height")) {  // keep the principal point centred as KITTI's roughly is
      cam.cx = cam.width * 0.4893;
      cam.cy = cam.height * 0.4926;
    }
    if (args.has("baseline")) cam.baseline_m = args.number("baseline");
    if (cam.width < 16 || cam.height < 16 || cam.baseline_m <= 0)
      throw binloop::CliError("bad image size or baseline");

    binloop::sim::SequenceJob job;
    job.route = route;
    job.times = times;
    job.start = static_cast<size_t>(args.integer("start"));
    job.end = args.has("end") ? static_cast<size_t>(args.integer("end")) : route.size() - 1;
    job.step = static_cast<size_t>(args.integer("step"));
    job.out_dir = args.str("out");
    if (std::filesystem::exists(job.out_dir) && !std::filesystem::is_empty(job.out_dir) && !args.has("force"))
      throw binloop::CliError(job.out_dir + ": exists and is not empty (use --force)");
    const uint64_t seed = static_cast<uint64_t>(args.integer("seed"));

    std::vector<std::string> photos;
    if (!args.has("procedural")) {
      photos = binloop::sim::defaultTexturePhotos();
      if (args.has("textures")) {
        for (const auto& f : binloop::listFilesNatural(args.str("textures"), {".png", ".jpg", ".jpeg"}))
          photos.push_back(f);
      }
    }
    auto bank = binloop::sim::TextureBank::build(photos, seed);
    std::cout << "render: "
              << (bank.photos_used ? std::to_string(bank.photos_used) + " photos" : "procedural") << " -> "
              << bank.textures.size() << " textures; camera " << cam.describe() << "\n";
    binloop::sim::WorldParams wp;
    wp.aperiodic_ground = args.has("aperiodic-ground");
    wp.rigid_ground = args.has("rigid-ground");
    const auto world = binloop::sim::World::build(route, std::move(bank), wp, seed);
    std::cout << "render: world of " << world.quads().size() << " quads along " << route.size()
              << " route poses\n";
    binloop::sim::RenderOptions ropt;
    ropt.noise_sigma = args.number("noise");
    ropt.exposure_swing = args.number("lighting");
    ropt.blur_sigma = args.number("blur");
    binloop::sim::StereoRenderer renderer(world, cam, ropt, seed);
    binloop::ProgressBar bar("render");
    const auto t0 = std::chrono::steady_clock::now();
    size_t frames = 0;
    binloop::sim::renderSequence(renderer, job, [&](size_t done, size_t total) {
      bar.update(done, total);
      frames = done;
    });
    bar.finish();
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::cout << "render: wrote " << frames << " stereo frames to " << job.out_dir << " in " << secs << " s ("
              << frames / secs << " frames/s)\n";
    return 0;
  });
}
