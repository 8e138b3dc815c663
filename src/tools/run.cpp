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

namespace fs = std::filesystem;
using namespace binloop;

int main(int argc, char** argv) {
  CliArgs args(
      "run",
      "scripts/binloop run <sequence_dir> --out <dir> [--config config/kitti.yaml]\n"
      "    [--detector hmvlad|hbow|fabmap|vlad|vladpq|none] [--shadow all|M,M] [--switch-detector-at KF:M]\n"
      "    [--lockstep | --rate R] [--seed N] [--start N] [--end N] [--reloc-vocab <hbow.bin>|none]\n"
      "    [--load-map <dir> [--localize-only]] [--save-map <dir>]\n"
      "Tracks and maps a KITTI-layout stereo sequence (image_0/, image_1/, calib.txt, times.txt), closes "
      "loops,\n"
      "and writes trajectory.kitti.txt / .tum.txt (every frame, loop-corrected), keyframes.kitti.txt / "
      ".tum.txt,\n"
      "timing.csv, loops.csv (one row per keyframe and model queried), summary.json.");
  args.positional("sequence_dir", "KITTI-layout sequence folder")
      .option("out", "output folder (created)")
      .option("config",
              "SLAM settings (YAML; see config/kitti.yaml); default: the built-in defaults, which that file "
              "repeats")
      .option("detector", "loop detector: hmvlad, hbow, fabmap, vlad, vladpq, or none (no loop closing)",
              "hmvlad")
      .option("vocab-dir", "where the detectors' model files are (<dir>/<model>.bin); default: the package's",
              packagePath(kShippedModelDir))
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
              "most recent keyframes are tried; default: the package's shipped k=8 L=5 vocabulary",
              packagePath(kRelocVocab))
      .option("load-map",
              "start in a map saved by --save-map or the ROS save_map service (tracking relocalises in it)")
      .option("save-map", "save the map at the end (one state file per stage, as the ROS save_map service)")
      .flag("localize-only",
            "with --load-map: track in the loaded map and make no keyframe (the map stays as loaded)")
      .flag("force-extractor",
            "use a vocabulary trained with other extractor settings than config's orb section");
  return runTool("run", [&] {
    if (!args.parse(argc, argv)) return 0;
    if (!args.has("out")) throw CliError("--out is required");
    const std::string detector = args.str("detector");
    const auto& names = placeModelNames();
    auto checkName = [&](const std::string& n, const std::string& what) {
      if (std::find(names.begin(), names.end(), n) == names.end())
        throw CliError(what + " '" + n + "': not one of hbow, fabmap, vlad, hmvlad, vladpq");
    };
    if (detector != "none") checkName(detector, "--detector");
    SlamConfig config = args.has("config") ? loadSlamConfig(args.str("config")) : SlamConfig{};
    config.tracker.seed = static_cast<uint64_t>(args.integer("seed"));
    if (args.has("localize-only")) {
      if (!args.has("load-map"))
        throw CliError("--localize-only needs a map to localise in: give --load-map");
      config.tracker.localize_only = true;
    }
    const std::string reloc_vocab = args.str("reloc-vocab");
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
              << seq.camera().describe();

    std::optional<LoopClosingSetup> loops;
    if (detector != "none") {
      LoopClosingSetup l;
      l.detector = config.detector;
      l.detector.model = detector;
      l.closer = config.closer;
      l.closer.verify.seed = config.tracker.seed;
      l.make_model = modelFileFactory(args.str("vocab-dir"), config.tracker.orb, args.has("force-extractor"),
                                      config.models);
      l.model_identity = modelFileIdentities(args.str("vocab-dir"));
      if (args.has("shadow")) {
        std::vector<std::string> skipped;
        l.shadow = shadowModelNames(args.str("shadow"), detector, args.str("vocab-dir"), &skipped);
        for (const std::string& n : skipped)
          std::cerr << "run: shadow model " << n << " skipped: no " << n << ".bin in "
                    << args.str("vocab-dir") << "\n";
      }
      if (args.has("switch-detector-at")) {
        std::stringstream ss(args.str("switch-detector-at"));
        std::string item;
        while (std::getline(ss, item, ',')) {
          const auto colon = item.find(':');
          if (colon == std::string::npos)
            throw CliError("--switch-detector-at '" + item + "': expected KF:model");
          size_t at = 0;
          try {
            at = std::stoul(item.substr(0, colon));
          } catch (const std::exception&) {
            throw CliError("--switch-detector-at '" + item + "': KF is not a number");
          }
          checkName(item.substr(colon + 1), "--switch-detector-at");
          l.switches.emplace_back(at, item.substr(colon + 1));
        }
      }
      loops = l;
    }
    SlamPipeline slam(seq.camera(), config.tracker, config.mapper,
                      lockstep ? PipelineMode::kLockStep : PipelineMode::kThreaded, 3, loops);
    if (args.has("load-map")) slam.loadMap(args.str("load-map"));
    std::vector<msg::TrackedFrame> frames;
    ProgressBar bar("run", static_cast<size_t>(end - start));
    const auto t0 = std::chrono::steady_clock::now();
    int problems = 0;
    double max_lag_s = 0;  // with --rate: how far behind the sequence's clock a frame went in
    for (long i = start; i < end; ++i) {
      if (rate > 0) {
        const auto due =
            t0 + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                     std::chrono::duration<double>((seq.times()[i] - seq.times()[start]) / rate));
        const auto now = std::chrono::steady_clock::now();
        if (now < due)
          std::this_thread::sleep_until(due);
        else
          max_lag_s = std::max(max_lag_s, std::chrono::duration<double>(now - due).count());
      }
      msg::TrackedFrame tf;
      try {
        tf = slam.process(seq.load(static_cast<size_t>(i)));
      } catch (const DataError& e) {  // an unreadable image: reported, skipped, the run goes on
        tf.frame_index = static_cast<uint64_t>(i);
        tf.stamp_s = seq.times()[i];
        tf.state = frames.empty() ? msg::TrackingState::kNotInitialized : msg::TrackingState::kLost;
        if (!frames.empty()) tf.T_w_c = frames.back().T_w_c;
        tf.problem = std::string(e.what()) + "; frame skipped";
      }
      if (!tf.problem.empty() && problems++ < 20)
        std::cerr << "\nrun: frame " << i << ": " << tf.problem << "\n";
      frames.push_back(tf);
      const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      std::ostringstream st;
      st << std::fixed << std::setprecision(1) << frames.size() / std::max(secs, 1e-9) << " frames/s, "
         << msg::toString(tf.state) << ", " << slam.tracker().map().keyframeCount() << " keyframes";
      bar.setStatus(st.str());
      bar.update(frames.size());
    }
    slam.finish();
    bar.finish();
    if (args.has("save-map")) {
      slam.saveMap(args.str("save-map"));
      std::cerr << "run: map saved in " << args.str("save-map") << "\n";
    }
    const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

    // Final poses: each frame rides on its reference keyframe as local mapping left it.
    const LocalMapper& mapper = slam.mapper();
    std::vector<Pose3> poses;
    Trajectory tum;
    for (const msg::TrackedFrame& tf : frames) {
      Pose3 T = tf.T_w_c, T_ref;
      if (tf.state != msg::TrackingState::kLost && tf.reference != kNoId &&
          mapper.keyframePose(tf.reference, &T_ref))
        T = T_ref * tf.T_ref_c;
      poses.push_back(T);
      tum.push_back({tf.stamp_s, T});
    }
    writeKittiPoses((out / "trajectory.kitti.txt").string(), poses);
    writeTumTrajectory((out / "trajectory.tum.txt").string(), tum);
    std::vector<Pose3> kf_poses;
    Trajectory kf_tum;
    for (const auto& k : mapper.keyframes()) {
      kf_poses.push_back(k.T_w_c);
      kf_tum.push_back({k.stamp_s, k.T_w_c});
    }
    writeKittiPoses((out / "keyframes.kitti.txt").string(), kf_poses);
    writeTumTrajectory((out / "keyframes.tum.txt").string(), kf_tum);

    std::map<SlamKeyframeId, const SlamPipeline::MappingTime*> map_time;
    for (const auto& m : slam.mappingTimes()) map_time[m.keyframe] = &m;
    std::ofstream timing(out / "timing.csv");
    timing << "frame,state,features,stereo_matches,tracked_points,keyframe,extract_ms,stereo_ms,track_ms,"
              "mapping_ms,ba_ms,triangulation_ms,points_triangulated\n";
    std::vector<double> ex, stt, tr, mp, ba, tri;
    int lost = 0, relocalized = 0;
    for (const msg::TrackedFrame& tf : frames) {
      const auto it = map_time.find(tf.new_keyframe);
      const bool kf = tf.new_keyframe != kNoId && it != map_time.end();
      timing << tf.frame_index << "," << msg::toString(tf.state) << "," << tf.features << ","
             << tf.stereo_matches << "," << tf.tracked_points << "," << (tf.new_keyframe != kNoId) << ","
             << tf.extract_ms << "," << tf.stereo_ms << "," << tf.track_ms << ","
             << (kf ? it->second->total_ms : 0) << "," << (kf ? it->second->ba_ms : 0) << ","
             << (kf ? it->second->triangulation_ms : 0) << "," << (kf ? it->second->points_triangulated : 0)
             << "\n";
      if (tf.features > 0) {
        ex.push_back(tf.extract_ms);
        stt.push_back(tf.stereo_ms);
        tr.push_back(tf.extract_ms + tf.stereo_ms + tf.track_ms);
      }
      lost += tf.state == msg::TrackingState::kLost;
      relocalized += tf.state == msg::TrackingState::kRelocalized;
    }
    for (const auto& m : slam.mappingTimes()) {
      mp.push_back(m.total_ms);
      ba.push_back(m.ba_ms);
      tri.push_back(m.triangulation_ms);
    }
    JsonObject js;
    js.add("sequence", seq.directory()).add("frames", frames.size()).add("start", start).add("end", end);
    js.add("keyframes", mapper.keyframeCount()).add("keyframes_made", slam.mappingTimes().size());
    js.add("map_points", mapper.pointCount()).add("lost_frames", lost).add("relocalizations", relocalized);
    js.add("problems", problems)
        .add("wall_s", wall_s)
        .add("frames_per_s", frames.size() / std::max(wall_s, 1e-9));
    js.add("mode", lockstep ? "lockstep" : "threaded").add("rate", rate).add("max_lag_s", max_lag_s);
    js.add("seed", args.integer("seed")).add("detector", detector);
    js.add("reloc_vocab", config.tracker.vocabulary ? reloc_vocab : std::string("none"));
    auto stat = [&](const std::string& name, const std::vector<double>& v) {
      js.add(name + "_ms_median", percentile(v, 0.5)).add(name + "_ms_p95", percentile(v, 0.95));
    };
    stat("extract", ex);
    stat("stereo", stt);
    stat("tracking_total", tr);
    stat("local_mapping", mp);
    stat("local_ba", ba);
    stat("triangulation", tri);
    if (slam.closesLoops()) {
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
        stat("detect_" + m, v);  // signature + query
        stat("detect_" + m + "_signature", signature_ms[m]);
        stat("detect_" + m + "_query", query_ms[m]);
      }
      stat("verify", verify_ms);
      stat("pose_graph", optimize_ms);
      stat("correction_apply", correction_ms);
      if (!switch_ms.empty()) stat("switch_rebuild", switch_ms);
      if (!global_ba_ms.empty()) stat("global_ba", global_ba_ms);
      const LocalMapper::GlobalBaStats& g = slam.mapper().globalBaStats();
      if (g.started > 0)  // threaded: in the background
        js.add("global_ba_background", JsonObject()
                                           .add("started", g.started)
                                           .add("merged", g.merged)
                                           .add("stopped_by_a_loop", g.aborted)
                                           .add("last_ms", g.last_ms)
                                           .add("last_keyframes", g.last_keyframes)
                                           .add("last_added_meanwhile", g.last_added_meanwhile));
      std::cout << "loops_accepted: " << by_status["accepted"] << "\n";
    }
    JsonObject settings(true);
    std::istringstream lines(describe(config));
    for (std::string line; std::getline(lines, line);) {
      const auto colon = line.find(": ");
      settings.addRaw(line.substr(0, colon), line.substr(colon + 2));
    }
    js.add("settings", settings);
    std::ofstream(out / "summary.json") << js.str();
    std::cout << "frames: " << frames.size() << "\nkeyframes: " << mapper.keyframeCount()
              << "\nmap_points: " << mapper.pointCount() << "\nlost_frames: " << lost
              << "\nframes_per_s: " << std::fixed << std::setprecision(1)
              << frames.size() / std::max(wall_s, 1e-9) << "\nresults: " << out.string() << "\n";
    return 0;
  });
}
