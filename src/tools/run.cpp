// run: the SLAM over a KITTI-layout sequence folder, offline (no ROS master). See docs/slam.md.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <thread>

#include "binloop/features/orb_slam_extractor.h"
#include "binloop/io/data_error.h"
#include "binloop/io/kitti_sequence.h"
#include "binloop/io/trajectory_io.h"
#include "binloop/pipeline/final_trajectory.h"
#include "binloop/pipeline/loop_log.h"
#include "binloop/pipeline/model_files.h"
#include "binloop/pipeline/slam_config.h"
#include "binloop/pipeline/slam_pipeline.h"
#include "binloop/place/hbow_recognizer.h"
#include "binloop/util/cli_args.h"
#include "binloop/util/json_object.h"
#include "binloop/util/package_paths.h"
#include "binloop/util/percentile.h"
#include "binloop/util/progress_bar.h"
#include "binloop/util/stopwatch.h"

namespace fs = std::filesystem;
using namespace binloop;

namespace {

void checkModelName(const std::string& n, const std::string& what) {
  const auto& names = placeModelNames();
  if (std::find(names.begin(), names.end(), n) == names.end())
    throw CliError(what + " '" + n + "': not one of hbow, fabmap, vlad, hmvlad, vladpq");
}

// "KF:model[,KF:model...]" of --switch-detector-at.
std::vector<std::pair<size_t, std::string>> parseSwitches(const std::string& text) {
  std::vector<std::pair<size_t, std::string>> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const auto colon = item.find(':');
    if (colon == std::string::npos) throw CliError("--switch-detector-at '" + item + "': expected KF:model");
    size_t at = 0;
    try {
      at = std::stoul(item.substr(0, colon));
    } catch (const std::exception&) {
      throw CliError("--switch-detector-at '" + item + "': KF is not a number");
    }
    checkModelName(item.substr(colon + 1), "--switch-detector-at");
    out.emplace_back(at, item.substr(colon + 1));
  }
  return out;
}

LoopClosingSetup loopClosingSetup(const CliArgs& args, const SlamConfig& config,
                                  const std::string& detector) {
  LoopClosingSetup l;
  l.detector = config.detector;
  l.detector.model = detector;
  l.closer = config.closer;
  l.closer.verify.seed = config.tracker.seed;
  const std::string dir =
      modelDirFor(args.str("vocab-dir"), config.tracker.orb.pattern == BriefPatternKind::kOrbLearned);
  l.make_model = modelFileFactory(dir, config.tracker.orb, args.has("force-extractor"), config.models);
  l.model_identity = modelFileIdentities(dir);
  if (args.has("shadow")) {
    std::vector<std::string> skipped;
    l.shadow = shadowModelNames(args.str("shadow"), detector, dir, &skipped);
    for (const std::string& n : skipped)
      std::cerr << "run: shadow model " << n << " skipped: no " << n << ".bin in " << dir << "\n";
  }
  if (args.has("switch-detector-at")) l.switches = parseSwitches(args.str("switch-detector-at"));
  return l;
}

// What the frame loop leaves: every frame's result, and how the run went.
struct Played {
  std::vector<msg::TrackedFrame> frames;
  int problems = 0;
  // Per frame: how far behind the clock it went in (0 when on time or without a rate), and the wall time the
  // SLAM took to return it, waits on the map included (where a lag builds up).
  std::vector<double> lag_ms, process_ms;
  double wall_s = 0;
};

// Feeds frames [start, end) to the SLAM, no faster than `rate` times the sequence's clock (0: flat out).
Played play(SlamPipeline& slam, const KittiSequence& seq, long start, long end, double rate) {
  Played p;
  ProgressBar bar("run", static_cast<size_t>(end - start));
  const auto t0 = std::chrono::steady_clock::now();
  for (long i = start; i < end; ++i) {
    // The images are read (PNG decoding) before the frame is due, as a camera's driver or a bag delivers
    // them already decoded: at 1x the decoding then falls in the wait, not on tracking's clock.
    std::optional<StereoFrame> frame;
    std::string skipped;  // why the frame is not tracked: an unreadable image
    try {
      frame = seq.load(static_cast<size_t>(i));
    } catch (const DataError& e) {
      skipped = e.what();
    }
    std::optional<std::chrono::steady_clock::time_point> due;
    double lag_s = 0;
    if (rate > 0) {
      due = t0 + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                     std::chrono::duration<double>((seq.times()[i] - seq.times()[start]) / rate));
      const auto now = std::chrono::steady_clock::now();
      if (now < *due)
        std::this_thread::sleep_until(*due);
      else
        lag_s = std::chrono::duration<double>(now - *due).count();
    }
    const auto handed = std::chrono::steady_clock::now();
    msg::TrackedFrame tf;
    if (frame) {
      try {
        tf = slam.process(*frame, due);
      } catch (const DataError& e) {
        skipped = e.what();
      }
    }
    if (!skipped.empty()) {  // reported, skipped, the run goes on
      tf.frame_index = static_cast<uint64_t>(i);
      tf.stamp_s = seq.times()[i];
      tf.state = p.frames.empty() ? msg::TrackingState::kNotInitialized : msg::TrackingState::kLost;
      if (!p.frames.empty()) tf.T_w_c = p.frames.back().T_w_c;
      tf.problem = skipped + "; frame skipped";
    }
    p.lag_ms.push_back(1e3 * lag_s);
    p.process_ms.push_back(1e3 *
                           std::chrono::duration<double>(std::chrono::steady_clock::now() - handed).count());
    if (!tf.problem.empty() && p.problems++ < 20)
      std::cerr << "\nrun: frame " << i << ": " << tf.problem << "\n";
    p.frames.push_back(tf);
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::ostringstream st;
    st << std::fixed << std::setprecision(1) << p.frames.size() / std::max(secs, 1e-9) << " frames/s, "
       << msg::toString(tf.state) << ", " << slam.tracker().map().keyframeCount() << " keyframes";
    bar.setStatus(st.str());
    bar.update(p.frames.size());
  }
  slam.finish();
  bar.finish();
  p.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return p;
}

void writeTrajectories(const fs::path& out, const std::vector<msg::TrackedFrame>& frames,
                       const LocalMapper& mapper) {
  writeTrajectoryFiles(
      (out / "trajectory").string(),
      finalTrajectory(frames, [&](SlamKeyframeId id, Pose3* T) { return mapper.keyframePose(id, T); }));
  Trajectory keyframes;
  for (const auto& k : mapper.keyframes()) keyframes.push_back({k.stamp_s, k.T_w_c});
  writeTrajectoryFiles((out / "keyframes").string(), keyframes);
  // Each frame where tracking put it at the time, before later loop corrections and BA moved its keyframe:
  // what a robot got live, and what tells odometry's errors from a correction's.
  Trajectory live;
  for (const auto& f : frames) live.push_back({f.stamp_s, f.T_w_c});
  writeTrajectoryFiles((out / "live").string(), live);
}

void addTimes(JsonObject& js, const std::string& name, const std::vector<double>& v) {
  js.add(name + "_ms_median", percentile(v, 0.5)).add(name + "_ms_p95", percentile(v, 0.95));
}

// What timing.csv shows, summed up for summary.json.
struct FrameStats {
  int lost = 0, relocalized = 0;
  std::vector<std::pair<std::string, std::vector<double>>> times;  // name, ms per frame or keyframe
};

// timing.csv: a row a frame, with its keyframe's mapping times.
FrameStats writeTiming(const fs::path& out, const Played& played, const SlamPipeline& slam) {
  const std::vector<msg::TrackedFrame>& frames = played.frames;
  std::map<SlamKeyframeId, const SlamPipeline::MappingTime*> map_time;
  for (const auto& m : slam.mappingTimes()) map_time[m.keyframe] = &m;
  std::ofstream timing(out / "timing.csv");
  timing << "frame,state,features,stereo_matches,tracked_points,keyframe,extract_ms,stereo_ms,track_ms,"
            "mapping_ms,ba_ms,triangulation_ms,points_triangulated,reference_points,mapping_queue,lag_ms,"
            "process_ms,apply_ms\n";
  std::vector<double> ex, stt, tr, mp, ba, tri;
  FrameStats s;
  for (size_t i = 0; i < frames.size(); ++i) {
    const msg::TrackedFrame& tf = frames[i];
    const auto it = map_time.find(tf.new_keyframe);
    const bool kf = tf.new_keyframe != kNoId && it != map_time.end();
    timing << tf.frame_index << "," << msg::toString(tf.state) << "," << tf.features << ","
           << tf.stereo_matches << "," << tf.tracked_points << "," << (tf.new_keyframe != kNoId) << ","
           << tf.extract_ms << "," << tf.stereo_ms << "," << tf.track_ms << ","
           << (kf ? it->second->total_ms : 0) << "," << (kf ? it->second->ba_ms : 0) << ","
           << (kf ? it->second->triangulation_ms : 0) << "," << (kf ? it->second->points_triangulated : 0)
           << "," << tf.reference_points << "," << tf.mapping_queue << "," << played.lag_ms[i] << ","
           << played.process_ms[i] << "," << tf.apply_ms << "\n";
    if (tf.features > 0) {
      ex.push_back(tf.extract_ms);
      stt.push_back(tf.stereo_ms);
      tr.push_back(tf.extract_ms + tf.stereo_ms + tf.track_ms);
    }
    s.lost += tf.state == msg::TrackingState::kLost;
    s.relocalized += tf.state == msg::TrackingState::kRelocalized;
  }
  for (const auto& m : slam.mappingTimes()) {
    mp.push_back(m.total_ms);
    ba.push_back(m.ba_ms);
    tri.push_back(m.triangulation_ms);
  }
  s.times = {{"extract", ex},       {"stereo", stt},  {"tracking_total", tr},
             {"local_mapping", mp}, {"local_ba", ba}, {"triangulation", tri}};
  return s;
}

// loops.csv and the summary's loop counts and times; returns the loops accepted.
int writeLoops(const fs::path& out, const SlamPipeline& slam, const KittiSequence& seq, JsonObject& js) {
  writeLoopLog((out / "loops.csv").string(), slam.loopLog(), seq.hasPoses() ? &seq.poses() : nullptr);
  std::map<std::string, int> by_status;
  std::map<std::string, std::vector<double>> detect_ms, query_ms, signature_ms;
  std::vector<double> verify_ms, optimize_ms, correction_ms, switch_ms, global_ba_ms;
  int queries = 0, proposals = 0, loop_problems = 0;
  for (const auto& e : slam.loopLog()) {
    if (!e.problem.empty()) {
      ++loop_problems;
      std::cerr << "run: loop detection: " << e.problem << "\n";
    }
    if (e.active) {
      ++queries;
      proposals += e.active->accepted != kNoId;
    }
    std::vector<msg::LoopCandidatesPtr> all = e.shadow;
    if (e.active) all.push_back(e.active);
    for (const auto& c : all) {
      const std::string m = c->model + (c->shadow ? "_shadow" : "");
      detect_ms[m].push_back(c->total_ms);
      double sig = 0;
      for (const auto& t : c->timings)
        if (t.step == "signature") sig += t.ms;
      signature_ms[m].push_back(sig);
      query_ms[m].push_back(c->total_ms - sig);
    }
    for (const auto& c : e.closures) {
      ++by_status[msg::loopStatusName(c->status)];
      if (c->verify_ms > 0) verify_ms.push_back(c->verify_ms);
      if (c->optimize_ms > 0) optimize_ms.push_back(c->optimize_ms);
    }
    if (e.correction_ms > 0) correction_ms.push_back(e.correction_ms);
    if (e.global_ba_ms > 0) global_ba_ms.push_back(e.global_ba_ms);
    if (e.switch_ms > 0) switch_ms.push_back(e.switch_ms);
  }
  js.add("loop_queries", queries).add("loop_proposals", proposals).add("loop_problems", loop_problems);
  js.add("loops_accepted", by_status["accepted"]);
  JsonObject statuses;
  for (const auto& [s, n] : by_status) statuses.add(s, n);
  js.add("loops_by_status", statuses);
  for (const auto& [m, v] : detect_ms) {
    addTimes(js, "detect_" + m, v);  // signature + query
    addTimes(js, "detect_" + m + "_signature", signature_ms[m]);
    addTimes(js, "detect_" + m + "_query", query_ms[m]);
  }
  addTimes(js, "verify", verify_ms);
  addTimes(js, "pose_graph", optimize_ms);
  addTimes(js, "correction_apply", correction_ms);
  if (!switch_ms.empty()) addTimes(js, "switch_rebuild", switch_ms);
  if (!global_ba_ms.empty()) addTimes(js, "global_ba", global_ba_ms);
  const LocalMapper::GlobalBaStats& g = slam.mapper().globalBaStats();
  if (g.started > 0)  // threaded: in the background
    js.add("global_ba_background", JsonObject()
                                       .add("started", g.started)
                                       .add("merged", g.merged)
                                       .add("stopped_by_a_loop", g.aborted)
                                       .add("last_added_meanwhile", g.last_added_meanwhile));
  const LocalMapper::LocalBaStats& l = slam.mapper().localBaStats();
  js.add("local_ba", JsonObject().add("runs", l.runs).add("cut_short", l.cut_short));
  if (g.last_keyframes > 0)  // the last global BA that reached the map, threaded or not
    js.add("global_ba_last", JsonObject()
                                 .add("ms", g.last.ms())
                                 .add("keyframes", g.last_keyframes)
                                 .add("iterations", g.last.iterations)
                                 .add("robust_iterations", g.last.robust_iterations)
                                 .add("outliers_removed", g.last.num_outliers)
                                 .add("initial_cost", g.last.initial_cost)
                                 .add("final_cost", g.last.final_cost));
  return by_status["accepted"];
}

JsonObject settingsRecord(const SlamConfig& config) {
  JsonObject settings(true);
  std::istringstream lines(describe(config));
  for (std::string line; std::getline(lines, line);) {
    const auto colon = line.find(": ");
    settings.addRaw(line.substr(0, colon), line.substr(colon + 2));
  }
  return settings;
}

CliArgs runArgs() {
  CliArgs args(
      "run",
      "scripts/binloop run <sequence_dir> --out <dir> [--config config/kitti.yaml]\n"
      "    [--detector hmvlad|hbow|fabmap|vlad|vladpq|none] [--shadow all|M,M] [--switch-detector-at KF:M]\n"
      "    [--lockstep | --rate R] [--seed N] [--start N] [--end N] [--reloc-vocab <hbow.bin>|none]\n"
      "    [--load-map <dir> [--localize-only]] [--save-map <dir>]\n"
      "Tracks and maps a KITTI-layout stereo sequence (image_0/, image_1/, calib.txt, times.txt), closes "
      "loops,\n"
      "and writes trajectory.kitti.txt / .tum.txt (every frame, loop-corrected), live.kitti.txt / .tum.txt\n"
      "(every frame as tracked at the time), keyframes.kitti.txt / .tum.txt,\n"
      "timing.csv, loops.csv (one row per keyframe and model queried), summary.json.");
  args.positional("sequence_dir", "KITTI-layout sequence folder")
      .option("out", "output folder (created)")
      .option("config",
              "SLAM settings (YAML; see config/kitti.yaml); default: the built-in defaults, which that file "
              "repeats")
      .option("detector", "loop detector: hmvlad, hbow, fabmap, vlad, vladpq, or none (no loop closing)",
              "hmvlad")
      .option("vocab-dir",
              "where the detectors' model files are (<dir>/<model>.bin); 'auto': the package's set made with "
              "the config's BRIEF tests (vocab/kitti08, or vocab/photos with orb.learned_pattern: 1)",
              kAutoVocab)
      .option("shadow", "models run beside the active one and only logged: 'all' or a comma list")
      .option("switch-detector-at",
              "KF:model[,KF:model...]: switch the active detector when it has seen KF keyframes")
      .flag("lockstep",
            "map every keyframe before the next frame (bit-identical reruns); default: mapping on its own "
            "thread")
      .option("rate",
              "threaded: frames go in no faster than R times the sequence's clock (times.txt), as from a "
              "camera or "
              "a bag played at R x; 0: as fast as tracking takes them",
              "0")
      .option("seed", "seed for every random choice (recorded in summary.json)", "1")
      .option("start", "first frame", "0")
      .option("end", "one past the last frame (default: all)", "-1")
      .option("reloc-vocab",
              "hbow vocabulary that indexes the keyframes for relocalisation anywhere in the map; 'none': "
              "only the "
              "most recent keyframes are tried; 'auto': the package's k=8 L=5 vocabulary made with the "
              "config's BRIEF tests (in the folder --vocab-dir auto picks)",
              kAutoVocab)
      .option("load-map",
              "start in a map saved by --save-map or the ROS save_map service (tracking relocalises in it)")
      .option("save-map", "save the map at the end (one state file per stage, as the ROS save_map service)")
      .flag("localize-only",
            "with --load-map: track in the loaded map and make no keyframe (the map stays as loaded)")
      .flag("force-extractor",
            "use a vocabulary trained with other extractor settings than config's orb section");
  return args;
}

}  // namespace

int main(int argc, char** argv) {
  CliArgs args = runArgs();
  return runTool("run", [&] {
    if (!args.parse(argc, argv)) return 0;
    if (!args.has("out")) throw CliError("--out is required");
    const std::string detector = args.str("detector");
    if (detector != "none") checkModelName(detector, "--detector");
    SlamConfig config = args.has("config") ? loadSlamConfig(args.str("config")) : SlamConfig{};
    config.tracker.seed = static_cast<uint64_t>(args.integer("seed"));
    if (args.has("localize-only")) {
      if (!args.has("load-map"))
        throw CliError("--localize-only needs a map to localise in: give --load-map");
      config.tracker.localize_only = true;
    }
    const std::string reloc_vocab =
        relocVocabFor(args.str("reloc-vocab"), config.tracker.orb.pattern == BriefPatternKind::kOrbLearned);
    if (reloc_vocab != "none") {
      config.tracker.vocabulary =
          loadRelocalisationVocabulary(reloc_vocab, config.tracker.orb, args.has("force-extractor"));
      config.tracker.vocabulary_identity = modelFileIdentity(reloc_vocab);
    }
    const KittiSequence seq = KittiSequence::open(args.str("sequence_dir"));
    const long start = args.integer("start");
    long end = args.integer("end");
    if (end < 0 || end > static_cast<long>(seq.size())) end = static_cast<long>(seq.size());
    if (start < 0 || start >= end)
      throw CliError("--start " + std::to_string(start) + " must lie in [0, " + std::to_string(end) + ")");
    const fs::path out = args.str("out");
    fs::create_directories(out);
    const bool lockstep = args.has("lockstep");
    const double rate = args.number("rate");
    if (!(rate >= 0) || rate > 1000)
      throw CliError("--rate " + args.str("rate") + ": 0 (flat out) or a factor up to 1000");
    if (rate > 0 && lockstep)
      throw CliError("--rate paces a threaded run; --lockstep waits for mapping at every keyframe");
    std::cerr << "run: " << seq.directory() << ", frames " << start << "-" << end - 1 << ", "
              << (lockstep ? "lock-step" : "threaded") << "\n"
              << seq.camera().describe() << "\n";

    std::optional<LoopClosingSetup> loops;
    if (detector != "none") loops = loopClosingSetup(args, config, detector);
    PipelineParams pipeline = config.pipeline;
    pipeline.mode = lockstep ? PipelineMode::kLockStep : PipelineMode::kThreaded;
    SlamPipeline slam(seq.camera(), config.tracker, config.mapper, pipeline, loops);
    if (args.has("load-map")) slam.loadMap(args.str("load-map"));
    const Played played = play(slam, seq, start, end, rate);
    if (args.has("save-map")) {
      const auto t0 = std::chrono::steady_clock::now();
      slam.saveMap(args.str("save-map"));
      std::cerr << "run: map saved in " << args.str("save-map") << " (" << std::fixed << std::setprecision(0)
                << msSince(t0) << " ms)\n";
    }

    const LocalMapper& mapper = slam.mapper();
    const std::vector<msg::TrackedFrame>& frames = played.frames;
    writeTrajectories(out, frames, mapper);
    const FrameStats stats = writeTiming(out, played, slam);
    const double fps = frames.size() / std::max(played.wall_s, 1e-9);
    const double max_lag_ms =
        played.lag_ms.empty() ? 0.0 : *std::max_element(played.lag_ms.begin(), played.lag_ms.end());
    JsonObject js;
    js.add("sequence", seq.directory()).add("frames", frames.size()).add("start", start).add("end", end);
    js.add("keyframes", mapper.keyframeCount()).add("keyframes_made", slam.mappingTimes().size());
    js.add("map_points", mapper.pointCount()).add("lost_frames", stats.lost);
    js.add("relocalizations", stats.relocalized).add("problems", played.problems);
    js.add("wall_s", played.wall_s).add("frames_per_s", fps);
    js.add("mode", lockstep ? "lockstep" : "threaded").add("rate", rate).add("max_lag_s", max_lag_ms / 1e3);
    js.add("seed", args.integer("seed")).add("detector", detector);
    js.add("reloc_vocab", config.tracker.vocabulary ? reloc_vocab : std::string("none"));
    for (const auto& [name, v] : stats.times) addTimes(js, name, v);
    if (slam.closesLoops()) std::cout << "loops_accepted: " << writeLoops(out, slam, seq, js) << "\n";
    js.add("settings", settingsRecord(config));
    std::ofstream(out / "summary.json") << js.str();
    std::cout << "frames: " << frames.size() << "\nkeyframes: " << mapper.keyframeCount()
              << "\nmap_points: " << mapper.pointCount() << "\nlost_frames: " << stats.lost
              << "\nframes_per_s: " << std::fixed << std::setprecision(1) << fps
              << "\nresults: " << out.string() << "\n";
    return 0;
  });
}
