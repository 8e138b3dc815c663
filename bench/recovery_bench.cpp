// Recovery benchmark: how tracking comes back after frames go missing, at several places of a rendered
// route (`render --aperiodic-ground`, the route's KITTI camera, seed 1; default 06). Frames
// start-lead..start-1 are mapped (all from frame 0 without --lead), `gap` frames are dropped, and the 30
// frames after the gap are scored against the ground truth carried into the map's frame at frame start-1
// (the map's own drift before the gap is not recovery's). Prints a table and, per gap, how many starts
// came back within 0.3 m (the SLAM issue's goal); never pass/fail. The default takes about 2 minutes on
// 2 cores. A lost first frame shows the motion model's error.
//   bench_recovery [--config file.yaml] [--gap N ...] [--route NN] [--start N ...] [--every N] [--lead N]
//                  [--reloc-vocab vocab/kitti08/hbow.bin] [--frames]
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "binloop/io/kitti_sequence.h"
#include "binloop/io/trajectory_io.h"
#include "binloop/pipeline/model_files.h"
#include "binloop/pipeline/slam_config.h"
#include "binloop/pipeline/slam_pipeline.h"
#include "binloop/sim/stereo_renderer.h"
#include "binloop/sim/texture_bank.h"
#include "binloop/util/cli_args.h"

using namespace binloop;

namespace {

constexpr int kAfter = 30;      // frames scored after each gap
constexpr double kGoalM = 0.3;  // the SLAM issue's bound on the poses after a 20-frame gap

struct Setup {
  std::string route = "06";
  std::vector<int> gaps{10, 20}, starts{100, 150, 200, 250, 300, 350};
  int every = 0;        // > 0: starts every this many frames along the whole route instead of `starts`
  int lead = 0;         // frames mapped before the gap; 0: all from frame 0
  bool frames = false;  // print each scored frame too
};

struct Outcome {
  std::string first_state;
  double first_m = 0, worst10_m = 0, worst30_m = 0;
  int lost = 0;
};

Outcome runGap(const std::map<int, StereoFrame>& frames, const std::vector<Pose3>& route,
               const StereoCamera& cam, const SlamConfig& config, int first, int start, int gap,
               bool print_frames) {
  SlamPipeline slam(cam, config.tracker, config.mapper, PipelineMode::kLockStep);
  Pose3 last, before_last;
  for (int i = first; i < start; ++i) {
    before_last = last;
    last = slam.process(frames.at(i)).T_w_c;
  }
  const Pose3 drift = last * route[start - 1].inverse();
  const Pose3 step = before_last.inverse() * last;  // the constant-velocity model's motion per frame
  Outcome o;
  for (int i = start + gap; i < start + gap + kAfter; ++i) {
    const msg::TrackedFrame tf = slam.process(frames.at(i));
    const double off = ((drift * route[i]).translation() - tf.T_w_c.translation()).norm();
    const bool lost = tf.state == msg::TrackingState::kLost;
    if (print_frames && i == start + gap) {
      Pose3 predicted = last;
      for (int k = start; k <= i; ++k) predicted = predicted * step;
      const Eigen::Vector3d e_p =
          predicted.linear().transpose() * (predicted.translation() - (drift * route[i]).translation());
      std::printf(
          "    constant velocity from frame %d predicts frame %d %.2f m off (right %.2f, ahead %.2f)\n",
          start - 1, i, e_p.norm(), e_p.x(), e_p.z());
    }
    if (print_frames) {
      // Where the error lies in the camera's own frame (x right, z ahead) tells a slide along the road
      // from a wrong turn.
      const Eigen::Vector3d e_c =
          tf.T_w_c.linear().transpose() * (tf.T_w_c.translation() - (drift * route[i]).translation());
      const double turn =
          Eigen::AngleAxisd((drift * route[i]).linear().transpose() * tf.T_w_c.linear()).angle();
      std::printf(
          "    frame %d: %s, %d tracked, error %.2f m (right %.2f, ahead %.2f), turned %.2f deg%s%s\n", i,
          msg::toString(tf.state), tf.tracked_points, off, e_c.x(), e_c.z(), turn * 180 / 3.14159265358979,
          tf.problem.empty() ? "" : ": ", tf.problem.c_str());
    }
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

int runBench(const SlamConfig& config, Setup setup) {
  const std::string poses = std::string(BINLOOP_SHARED_DATA_DIR) + "/kitti/poses/" + setup.route + ".txt";
  if (!std::filesystem::exists(poses)) {
    std::fprintf(stderr, "bench_recovery: needs %s\n", poses.c_str());
    return 1;
  }
  const std::vector<Pose3> route = readKittiPoses(poses);
  const int max_gap = *std::max_element(setup.gaps.begin(), setup.gaps.end());
  if (setup.every > 0) {
    setup.starts.clear();
    for (int s = std::max(setup.every, setup.lead); s + max_gap + kAfter <= static_cast<int>(route.size());
         s += setup.every)
      setup.starts.push_back(s);
  }
  for (int start : setup.starts)
    if (start < 1 || start - setup.lead < 0 || start + max_gap + kAfter > static_cast<int>(route.size()))
      throw CliError("--start " + std::to_string(start) + ": route " + setup.route + " has " +
                     std::to_string(route.size()) + " frames; a start needs " + std::to_string(setup.lead) +
                     " before it and the gap plus " + std::to_string(kAfter) + " after it");
  const StereoCamera cam = kittiCameraByName("kitti" + setup.route);
  sim::WorldParams wp;
  wp.aperiodic_ground = true;
  const auto world = sim::World::build(route, sim::TextureBank::build(sim::defaultTexturePhotos(), 1), wp, 1);
  sim::StereoRenderer renderer(world, cam, {}, 1);
  std::printf(
      "Rendered %s (aperiodic ground): %s, then `gap` frames missing; errors of the %d frames after the "
      "gap, lost frames left out of the worst; `skipped` is how far the camera moved meanwhile.\n\n",
      setup.route.c_str(),
      setup.lead > 0 ? ("the " + std::to_string(setup.lead) + " frames before `start` mapped").c_str()
                     : "frames 0..start-1 mapped",
      kAfter);
  std::printf(
      "| start | gap | skipped | first frame | its error | worst, 10 frames | worst, %d frames | lost |\n",
      kAfter);
  std::printf("|---|---|---|---|---|---|---|---|\n");
  std::map<int, std::vector<double>> worst_by_gap;  // lost frames count as failing the goal
  std::map<int, int> first_ok, all_ok;
  for (int gap : setup.gaps)
    for (int start : setup.starts) {
      // Only the frames this start uses are rendered (a whole route at once would not fit in memory).
      const int first = setup.lead > 0 ? start - setup.lead : 0;
      std::map<int, StereoFrame> frames;
      auto add = [&](int from, int to) {
        const auto rendered =
            sim::renderFrames(renderer, route, static_cast<size_t>(from), static_cast<size_t>(to - from));
        for (int i = from; i < to; ++i) {
          StereoFrame f = rendered[static_cast<size_t>(i - from)];
          f.index = i;  // renderFrames counts from its first frame; the tracker needs the route's clock
          f.stamp_s = 0.1 * i;
          frames.emplace(i, std::move(f));
        }
      };
      add(first, start);
      add(start + gap, start + gap + kAfter);
      const Outcome o = runGap(frames, route, cam, config, first, start, gap, setup.frames);
      const double skipped = (route[start + gap].translation() - route[start - 1].translation()).norm();
      std::printf("| %d | %d | %.1f m | %s | %.2f m | %.2f m | %.2f m | %d |\n", start, gap, skipped,
                  o.first_state.c_str(), o.first_m, o.worst10_m, o.worst30_m, o.lost);
      std::fflush(stdout);
      const bool first_lost = o.first_state == msg::toString(msg::TrackingState::kLost);
      first_ok[gap] += !first_lost && o.first_m <= kGoalM;
      all_ok[gap] += o.lost == 0 && o.worst30_m <= kGoalM;
      worst_by_gap[gap].push_back(o.lost > 0 ? 1e9 : o.worst30_m);
    }
  std::printf("\n");
  for (int gap : setup.gaps) {
    std::vector<double>& w = worst_by_gap[gap];
    std::sort(w.begin(), w.end());
    const double median = w[w.size() / 2];
    char median_text[32] = "a lost frame";
    if (median < 1e9) std::snprintf(median_text, sizeof median_text, "%.2f m", median);
    std::printf(
        "gap %d: %d of %zu starts within %.1f m on the first frame after it, %d on all %d (none lost); "
        "median worst over the %d: %s\n",
        gap, first_ok[gap], w.size(), kGoalM, all_ok[gap], kAfter, kAfter, median_text);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CliArgs args("bench_recovery",
               "bench_recovery [--config file.yaml] [--gap N ...] [--route NN] [--start N ... | --every N] "
               "[--lead N]");
  args.option("config", "SLAM settings (config/kitti.yaml's keys); default: the built-in ones")
      .option("gap", "frames dropped; repeat for several (default: 10 and 20)")
      .option("route", "KITTI route whose ground truth is rendered (default: 06)")
      .option("start", "first missing frame; repeat for several (default: 100, 150, ..., 350)")
      .option("every", "starts every N frames along the whole route instead (needs --lead)")
      .option("lead", "frames mapped before each gap (default: all from frame 0)")
      .option("reloc-vocab",
              "hbow vocabulary for relocalisation anywhere in the map, as `run` loads by default "
              "(vocab/kitti08/hbow.bin); default: none, only the most recent keyframes")
      .flag("frames",
            "also print each scored frame: state, error along and across the view, rotation error, problem");
  return runTool("bench_recovery", [&] {
    if (!args.parse(argc, argv)) return 0;
    SlamConfig config = args.has("config") ? loadSlamConfig(args.str("config")) : SlamConfig{};
    if (args.has("reloc-vocab"))
      config.tracker.vocabulary =
          loadRelocalisationVocabulary(args.str("reloc-vocab"), config.tracker.orb, false);
    auto count = [](const std::string& option, const std::string& v) {
      if (v.empty() || v.size() > 6 || v.find_first_not_of("0123456789") != std::string::npos ||
          std::stoi(v) < 1)
        throw CliError("--" + option + " '" + v + "': a whole number, at least 1");
      return std::stoi(v);
    };
    Setup setup;
    if (!args.all("gap").empty()) setup.gaps.clear();
    for (const std::string& g : args.all("gap")) setup.gaps.push_back(count("gap", g));
    if (args.has("route")) {
      setup.route = args.str("route");
      if (setup.route.size() != 2 || setup.route.find_first_not_of("0123456789") != std::string::npos ||
          setup.route > "10")
        throw CliError("--route '" + setup.route + "': a KITTI route with ground truth, two digits (00-10)");
    }
    setup.frames = args.has("frames");
    if (args.has("lead")) setup.lead = count("lead", args.str("lead"));
    if (args.has("start") && args.has("every")) throw CliError("--start and --every: give one of them");
    if (!args.all("start").empty()) setup.starts.clear();
    for (const std::string& s : args.all("start")) setup.starts.push_back(count("start", s));
    if (args.has("every")) {
      if (setup.lead == 0)
        throw CliError("--every needs --lead (mapping from frame 0 for every start would take hours)");
      setup.every = count("every", args.str("every"));
    }
    return runBench(config, setup);
  });
}
