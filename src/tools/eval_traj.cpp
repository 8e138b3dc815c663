// eval-traj: an estimated trajectory against KITTI ground truth: ATE RMSE after SE(3) alignment and the
// KITTI devkit's relative errors (docs/tools.md). One `key: value` per line, or one JSON object.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "binloop/eval/trajectory_metrics.h"
#include "binloop/eval/trajectory_plot.h"
#include "binloop/eval/turn_tilt.h"
#include "binloop/io/data_error.h"
#include "binloop/io/trajectory_io.h"
#include "binloop/util/cli_args.h"
#include "binloop/util/json_object.h"

using namespace binloop;

namespace {

std::string fmt(double v) {
  if (!std::isfinite(v)) return "nan";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

}  // namespace

int main(int argc, char** argv) {
  CliArgs args("eval-traj",
               "eval-traj --gt <poses.txt> --est <trajectory.txt> [--times times.txt] [--match index|time] "
               "[--plot out.png] [--turns] [--json]");
  args.option("gt", "ground truth, KITTI format (12 numbers per line, one line per frame)")
      .option("est",
              "estimate: KITTI (12 numbers per line; line i = frame i) or TUM (stamp tx ty tz qx qy qz qw; "
              "any subset of frames, e.g. keyframes); the format is told by the first line")
      .option("times", "the ground truth's times.txt: TUM stamps are matched to it")
      .option("match",
              "how TUM stamps find their frames: 'time' (needs --times) or 'index' (stamps are frame "
              "indices); default: time with --times, else an error. KITTI files are always by index")
      .option("tolerance-ms", "time matching: largest difference between a stamp and its frame's time", "1")
      .option("stamp-offset",
              "time matching: the estimate's stamps are times.txt + this many seconds "
              "(1 for trajectories made from kitti2bag's bags)",
              "0")
      .option("plot", "write a top view (x-z plane) of both trajectories to this PNG")
      .flag("turns",
            "also the tilt each sharp turn of the ground truth leaves in the estimate (degrees, about the "
            "horizontal axes; the estimate may be in any world, e.g. a run started mid-route), turn by turn")
      .flag("json", "print one JSON object instead of 'key: value' lines");
  return runTool("eval-traj", [&] {
    if (!args.parse(argc, argv)) return 0;
    for (const char* o : {"gt", "est"})
      if (!args.has(o)) throw CliError(std::string("--") + o + " is required");
    const std::string gt_path = args.str("gt"), est_path = args.str("est");
    const std::vector<Pose3> gt = readGroundTruthPoses(gt_path);
    const EstimateFile est = readEstimateFile(est_path);
    const bool kitti = est.format == TrajectoryFormat::kitti;

    std::string match = args.str("match");
    if (match.empty()) match = kitti || !args.has("times") ? "index" : "time";
    if (match != "index" && match != "time")
      throw CliError("--match must be 'index' or 'time', not '" + match + "'");
    if (kitti && match == "time")
      throw CliError("--match time: KITTI files carry no stamps (line i is frame i)");
    if (!kitti && !args.has("match") && !args.has("times"))
      throw CliError(est_path +
                     " is a TUM file: give the ground truth's --times to match its stamps, or "
                     "--match index when its stamps are frame indices");
    if (match == "time" && !args.has("times")) throw CliError("--match time needs --times");

    MatchedPoses m;
    if (match == "time") {
      TimeMatchOptions o;
      o.tolerance_s = args.number("tolerance-ms") * 1e-3;
      o.stamp_offset_s = args.number("stamp-offset");
      const std::vector<double> times = readTimes(args.str("times"));
      try {
        m = matchByTime(gt, times, est, o, est_path);
      } catch (const DataError& e) {
        // A constant offset (kitti2bag's bags run 1 s ahead of times.txt) is the likely cause: name it.
        if (times.empty() || std::string(e.what()).find("nearest ground-truth time") == std::string::npos)
          throw;
        throw DataError(std::string(e.what()) + "; the first stamp is " +
                        fmt(est.poses.front().stamp_s - o.stamp_offset_s - times.front()) +
                        " s after the first time: if every stamp is offset by as much, pass --stamp-offset");
      }
    } else {
      m = matchByFrameIndex(gt, est, est_path);
    }
    if (kitti && est.poses.size() < gt.size())
      std::cerr << "eval-traj: note: " << est_path << " has " << est.poses.size() << " poses for "
                << gt.size() << " ground-truth frames, so it is taken as frames 0.." << est.poses.size() - 1
                << " (an estimate of keyframes only must be a TUM file)\n";
    const TrajectoryMetrics tm = evaluateTrajectory(m);
    const RelativeErrors& rel = tm.relative;
    std::vector<TurnTilt> tilts;
    double tilt_sum = 0;
    if (args.has("turns")) {
      tilts = tiltLeftByTurns(m, sharpTurns(gt));
      for (const TurnTilt& t : tilts) tilt_sum += t.tilt_deg;
    }

    if (args.has("plot")) {
      std::vector<Pose3> aligned;
      for (const auto& T : m.est) aligned.push_back(tm.T_gt_est * T);
      const std::string title = std::filesystem::path(est_path).filename().string() + " vs " +
                                std::filesystem::path(gt_path).filename().string() + ", " +
                                std::to_string(m.frames.size()) + " of " + std::to_string(gt.size()) +
                                " frames";
      // The ground truth the estimate covers (all of it unless the estimate starts late or stops early).
      const std::vector<Pose3> gt_span(gt.begin() + m.frames.front(), gt.begin() + m.frames.back() + 1);
      writeTrajectoryPlot(args.str("plot"), title, gt_span, aligned, tm);
    }

    const std::string format =
        std::string(formatName(est.format)) + (kitti ? " (12 numbers per line)" : " (8 numbers per line)");
    const std::string matched = m.rule + ", " + std::to_string(m.frames.size()) + " of " +
                                std::to_string(gt.size()) + " ground-truth frames";
    std::ostringstream out;
    if (args.has("json")) {
      JsonObject j;
      j.add("gt", gt_path)
          .add("est", est_path)
          .add("format", formatName(est.format))
          .add("matched", matched)
          .add("frames", m.frames.size())
          .add("gt_frames", gt.size())
          .add("path_length_m", rel.path_length_m)
          .add("segments", rel.segments)
          .add("ate_rmse_m", tm.ate_rmse_m)
          .add("t_rel_pct", rel.t_rel_pct)
          .add("r_rel_deg_per_100m", rel.r_rel_deg_per_100m);
      if (!rel.valid) j.add("relative_note", rel.reason);
      if (args.has("plot")) j.add("plot", args.str("plot"));
      if (args.has("turns")) {
        std::string list = "[";
        for (size_t i = 0; i < tilts.size(); ++i) {
          JsonObject t;
          t.add("first", tilts[i].turn.first)
              .add("last", tilts[i].turn.last)
              .add("tilt_deg", tilts[i].tilt_deg);
          list += (i ? ", " : "") + t.str(1);
        }
        j.add("turn_tilt_deg_sum", tilt_sum).addRaw("turn_tilts", list + "]");
      }
      out << j.str();
    } else {
      out << "gt: " << gt_path << ", " << gt.size() << " poses\n"
          << "estimate: " << est_path << ", " << format << ", " << est.poses.size() << " poses\n"
          << "matched: " << matched << "\n"
          << "frames: " << m.frames.size() << "\n"
          << "path_length_m: " << fmt(rel.path_length_m) << "\n"
          << "segments: " << rel.segments << "\n"
          << "ate_rmse_m: " << fmt(tm.ate_rmse_m) << "\n"
          << "t_rel_pct: " << fmt(rel.t_rel_pct) << "\n"
          << "r_rel_deg_per_100m: " << fmt(rel.r_rel_deg_per_100m) << "\n";
      if (!rel.valid) out << "relative_note: " << rel.reason << "\n";
      if (args.has("plot")) out << "plot: " << args.str("plot") << "\n";
      if (args.has("turns")) {
        out << "turn_tilt_deg_sum: " << fmt(tilt_sum) << " (" << tilts.size() << " turns)\n";
        for (const TurnTilt& t : tilts)
          out << "turn_tilt_deg: frames " << t.turn.first << "-" << t.turn.last << " " << fmt(t.tilt_deg)
              << "\n";
      }
    }
    std::cout << out.str();
    return 0;
  });
}
