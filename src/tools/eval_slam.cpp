// eval-slam: the SLAM once per loop detector over one sequence (the `run` tool as child processes), scored
// side by side: trajectory accuracy, loops against ground truth, detection and verification timings.
// See docs/tools.md, and eval/slam_evaluation.h for what counts as a correct loop and a closed revisit.
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <thread>

#include "binloop/eval/accuracy_table.h"
#include "binloop/eval/loop_ground_truth.h"
#include "binloop/eval/slam_evaluation.h"
#include "binloop/eval/trajectory_metrics.h"
#include "binloop/eval/trajectory_plot.h"
#include "binloop/io/data_error.h"
#include "binloop/io/json_fields.h"
#include "binloop/io/trajectory_io.h"
#include "binloop/pipeline/loop_log.h"
#include "binloop/place/place_recognizer.h"
#include "binloop/util/cli_args.h"
#include "binloop/util/fixed_decimals.h"

namespace fs = std::filesystem;
using namespace binloop;

namespace {

std::vector<std::string> split(const std::string& s, const std::string& separators) {
  std::vector<std::string> out;
  for (size_t i = s.find_first_not_of(separators); i != std::string::npos;
       i = s.find_first_not_of(separators, i)) {
    const size_t e = s.find_first_of(separators, i);
    out.push_back(s.substr(i, e - i));
    i = e;
  }
  return out;
}

std::string fixed(double v, int decimals) { return std::isfinite(v) ? fixedDecimals(v, decimals) : "n/a"; }

// Starts `argv` with stdin from /dev/null and stdout and stderr into `log` (after a line naming the command).
pid_t launch(const std::vector<std::string>& argv, const std::string& log) {
  {
    std::ofstream head(log);
    head << "eval-slam:";
    for (const auto& a : argv) head << " " << a;
    head << "\n";
  }
  const int fd = ::open(log.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
  if (fd < 0) throw DataError(log + ": cannot write (" + std::strerror(errno) + ")");
  std::vector<char*> cargv;
  for (const auto& a : argv) cargv.push_back(const_cast<char*>(a.c_str()));
  cargv.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fd);
    throw std::runtime_error(std::string("cannot start a process: ") + std::strerror(errno));
  }
  if (pid == 0) {  // child: only async-signal-safe calls from here
    const int in = ::open("/dev/null", O_RDONLY);
    if (in >= 0) ::dup2(in, 0);
    ::dup2(fd, 1);
    ::dup2(fd, 2);
    ::execv(cargv[0], cargv.data());
    const char msg[] = "eval-slam: cannot execute the run tool\n";
    [[maybe_unused]] const ssize_t n = ::write(2, msg, sizeof msg - 1);
    ::_exit(127);
  }
  ::close(fd);
  return pid;
}

// One model's row of the table; `failure` empty when it was scored.
struct Row {
  std::string model, failure;
  std::string name;  // the model, or "<model>/run-<k>" when each model runs several times
  fs::path dir;      // where its run writes
  int lost_frames = 0;
  TrajectoryMetrics tm;
  LoopScore loops;
  double detect_median = NAN, detect_p95 = NAN, query_median = NAN, signature_median = NAN,
         verify_median = NAN;
  std::vector<Pose3> aligned;
  int first_frame = 0, last_frame = 0;
  bool pose_judged = false;  // loops.csv had every accepted loop's relative pose
};

void score(Row& row, const fs::path& dir, const std::vector<Pose3>& gt,
           const std::vector<RevisitSegment>& segments) {
  if (!fs::is_directory(dir)) throw DataError(dir.string() + ": no such folder");
  const fs::path summary = dir / "summary.json";
  std::ifstream in(summary);
  if (!in) throw DataError(summary.string() + ": missing (run did not get as far as writing it)");
  const JsonFields json = readJsonFields(
      std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>()), summary.string());
  // A KITTI trajectory's line i is frame start + i, but scoring takes it as frame i.
  if (jsonNumber(json, "start") > 0)
    throw DataError(summary.string() + ": the run started at frame " + json.at("start") +
                    ", so trajectory.kitti.txt's lines are not frame numbers; run from frame 0");
  const std::string detector = json.count("detector") ? json.at("detector") : "";
  if (detector != row.model)
    throw DataError(summary.string() + ": a run with detector '" + detector + "', not '" + row.model + "'");

  const std::string traj = (dir / "trajectory.kitti.txt").string();
  const MatchedPoses m = matchByFrameIndex(gt, readEstimateFile(traj), traj);
  row.tm = evaluateTrajectory(m);
  for (const auto& T : m.est) row.aligned.push_back(row.tm.T_gt_est * T);
  row.first_frame = m.frames.front();
  row.last_frame = m.frames.back();

  std::vector<std::pair<int, int>> accepted;
  std::vector<Pose3> poses;  // their relative poses, when the log has them
  bool all_posed = true;
  if (row.model != "none")  // run writes no loops.csv without a detector
    for (const LoggedLoop& l : readLoopLog((dir / "loops.csv").string()))
      if (l.status == msg::LoopStatus::kAccepted) {
        accepted.emplace_back(static_cast<int>(l.query_frame), static_cast<int>(l.match_frame));
        poses.push_back(l.T_query_match);
        all_posed = all_posed && l.has_pose;
      }
  row.pose_judged = all_posed;
  row.loops = all_posed ? scoreLoops(accepted, poses, gt, segments) : scoreLoops(accepted, gt, segments);

  const double lost =
      jsonNumber(json, "lost_frames");  // NaN when a summary lacks it: casting that is undefined
  row.lost_frames = std::isfinite(lost) ? static_cast<int>(lost) : 0;
  row.detect_median = jsonNumber(json, "detect_" + row.model + "_ms_median");
  row.detect_p95 = jsonNumber(json, "detect_" + row.model + "_ms_p95");
  row.query_median = jsonNumber(json, "detect_" + row.model + "_query_ms_median");
  row.signature_median = jsonNumber(json, "detect_" + row.model + "_signature_ms_median");
  row.verify_median = jsonNumber(json, "verify_ms_median");
}

std::string csvCell(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string o = "\"";
  for (char c : s) o += c == '"' ? std::string("\"\"") : std::string(1, c);
  return o + "\"";
}

}  // namespace

int main(int argc, char** argv) {
  CliArgs args(
      "eval-slam",
      "scripts/binloop eval-slam --sequence <dir> --out <dir> [--detectors all|hbow,fabmap,...,none]\n"
      "    [--loop-gt loops.txt] [--jobs N] [--config config/kitti.yaml] [--lockstep] [--run-args \"...\"]\n"
      "    [--score-only] [--runs N] [--reference <peer dir>]\n"
      "Runs the SLAM (the run tool) once per detector into <out>/<detector>/ (its output in run.log there),\n"
      "scores each against <sequence>/poses.txt and the loop ground truth, and writes <out>/summary.csv\n"
      "(also printed) and <out>/trajectories.png. With --runs N > 1 each detector runs N times into\n"
      "<out>/<detector>/run-<k>/ and <out>/accuracy.csv sums them up (median, min-max, loops wrong in any\n"
      "run, revisits closed in every run), beside a peer's runs when --reference names their folder.\n"
      "Exits 1 when a run failed or could not be scored.");
  args.option("sequence", "KITTI-layout sequence folder with poses.txt (the ground truth)")
      .option("out", "output folder: one folder per detector, summary.csv, trajectories.png")
      .option("detectors",
              "comma list of hbow, fabmap, vlad, hmvlad, vladpq, none (no loop closing); 'all' stands "
              "for the five models",
              "all")
      .option("loop-gt",
              "loop ground truth, 'query_frame ref_frame' per line ('#' comments); default: pairs of "
              "poses within 6 m and more than 300 frames apart")
      .option("jobs", "runs at the same time (default: the number of cores)")
      .option("config", "passed to run")
      .flag("lockstep", "passed to run")
      .option("run-args", "more arguments for run, split at spaces (no quoting), e.g. \"--end 60 --seed 2\"")
      .flag("score-only", "run nothing: score the <out>/<detector>/ folders already there")
      .option("runs", "runs of each detector; more than 1: median and range in <out>/accuracy.csv", "1")
      .option("reference",
              "a peer's run folders to score by the same rules (sub-folders with CameraTrajectory.txt, "
              "loops.txt, TrackingTimes.txt, e.g. ORB-SLAM2's reference results for this sequence)");
  return runTool("eval-slam", [&] {
    if (!args.parse(argc, argv)) return 0;
    for (const char* o : {"sequence", "out"})
      if (!args.has(o)) throw CliError(std::string("--") + o + " is required");
    std::vector<std::string> models;
    const auto& names = placeModelNames();
    for (const auto& m : split(args.str("detectors"), ","))
      if (m == "all")
        models.insert(models.end(), names.begin(), names.end());
      else
        models.push_back(m);
    if (models.empty()) throw CliError("--detectors is empty");
    for (size_t i = 0; i < models.size(); ++i) {
      if (models[i] != "none" && std::find(names.begin(), names.end(), models[i]) == names.end())
        throw CliError("--detectors: unknown detector '" + models[i] +
                       "': not one of hbow, fabmap, vlad, hmvlad, "
                       "vladpq, none (or all)");
      if (std::find(models.begin(), models.begin() + i, models[i]) != models.begin() + i)
        throw CliError("--detectors: '" + models[i] + "' is named twice");
    }
    const long runs = args.integer("runs");
    if (runs < 1) throw CliError("--runs must be >= 1");
    const long jobs =
        args.has("jobs") ? args.integer("jobs") : std::max(1u, std::thread::hardware_concurrency());
    if (jobs < 1) throw CliError("--jobs must be >= 1");
    const std::vector<std::string> run_args = split(args.str("run-args"), " \t");
    for (const auto& a : run_args) {
      const std::string name = a.substr(0, a.find('='));
      if (name == "--out" || name == "--detector")
        throw CliError("--run-args: " + name + " is set by eval-slam");
      if (name == "--start")
        throw CliError(
            "--run-args: --start is not supported (trajectory.kitti.txt's lines are scored as frames 0, 1, "
            "...)");
    }

    // The ground truth and the revisits before any run: their errors should not wait for the SLAM.
    const fs::path seq = args.str("sequence"), out = args.str("out");
    if (!fs::is_directory(seq)) throw DataError(seq.string() + ": no such folder");
    const fs::path poses_path = seq / "poses.txt";
    if (!fs::exists(poses_path))
      throw DataError(poses_path.string() +
                      ": no such file (eval-slam scores against the sequence's ground truth)");
    const std::vector<Pose3> gt = readGroundTruthPoses(poses_path.string());
    std::vector<std::pair<int, int>> pairs;
    std::string gt_source;
    if (args.has("loop-gt")) {
      gt_source = args.str("loop-gt");
      pairs = readIndexPairs(gt_source);
      for (const auto& [q, r] : pairs)
        if (q >= static_cast<int>(gt.size()) || r >= static_cast<int>(gt.size()))
          throw DataError(gt_source + ": pair " + std::to_string(q) + " " + std::to_string(r) +
                          " is outside the " + std::to_string(gt.size()) + " poses of " +
                          poses_path.string());
    } else {
      pairs = loopPairsFromPoses(gt, 6.0, 300);
      gt_source = "poses within 6 m, more than 300 frames apart";
    }
    const std::vector<RevisitSegment> segments = revisitSegments(pairs);
    std::cout << "eval-slam: " << seq.string() << ", " << gt.size() << " ground-truth poses; revisits ("
              << gt_source << "): " << segments.size() << " segment" << (segments.size() == 1 ? "" : "s");
    for (size_t i = 0; i < segments.size(); ++i)
      std::cout << (i ? ", " : " at query frames ") << segments[i].first << "-" << segments[i].last;
    std::cout << "\n";

    std::vector<Row> rows;
    for (const std::string& m : models)
      for (long k = 1; k <= runs; ++k) {
        Row r;
        r.model = m;
        r.name = runs == 1 ? m : m + "/run-" + std::to_string(k);
        r.dir = out / r.name;
        rows.push_back(r);
      }
    if (!args.has("score-only")) {
      std::error_code ec;
      fs::path self = fs::read_symlink("/proc/self/exe", ec);
      if (ec) self = fs::absolute(argv[0]);
      const fs::path run_bin = self.parent_path() / "run";
      if (::access(run_bin.c_str(), X_OK) != 0)
        throw DataError(run_bin.string() +
                        ": the run tool is not there (eval-slam runs the one beside itself)");
      std::map<pid_t, size_t> running;
      std::map<size_t, std::chrono::steady_clock::time_point> started;
      size_t next = 0;
      while (next < rows.size() || !running.empty()) {
        while (next < rows.size() && static_cast<long>(running.size()) < jobs) {
          const fs::path dir = rows[next].dir;
          fs::create_directories(dir);
          // A failed run must not leave an earlier run's results to be scored as its own.
          for (const char* f : {"trajectory.kitti.txt", "loops.csv", "summary.json"}) fs::remove(dir / f);
          std::vector<std::string> cmd{run_bin.string(), seq.string(), "--out",
                                       dir.string(),     "--detector", rows[next].model};
          if (args.has("lockstep")) cmd.push_back("--lockstep");
          if (args.has("config")) cmd.insert(cmd.end(), {"--config", args.str("config")});
          cmd.insert(cmd.end(), run_args.begin(), run_args.end());
          running[launch(cmd, (dir / "run.log").string())] = next;
          started[next] = std::chrono::steady_clock::now();
          std::cerr << "eval-slam: " << rows[next].name << ": running (log " << (dir / "run.log").string()
                    << ")\n";
          ++next;
        }
        int status = 0;
        const pid_t pid = ::waitpid(-1, &status, 0);
        if (pid < 0) {
          if (errno == EINTR) continue;
          throw std::runtime_error(std::string("waiting for the runs: ") + std::strerror(errno));
        }
        const auto it = running.find(pid);
        if (it == running.end()) continue;
        Row& row = rows[it->second];
        const double secs =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - started[it->second]).count();
        const std::string log = (row.dir / "run.log").string();
        if (WIFEXITED(status) && WEXITSTATUS(status) == 0)
          std::cerr << "eval-slam: " << row.name << ": done in " << fixed(secs, 0) << " s\n";
        else
          row.failure = (WIFEXITED(status) ? "run exited with " + std::to_string(WEXITSTATUS(status))
                                           : "run killed by signal " + std::to_string(WTERMSIG(status))) +
                        ", see " + log;
        if (!row.failure.empty()) std::cerr << "eval-slam: " << row.name << ": " << row.failure << "\n";
        running.erase(it);
      }
    }
    for (Row& row : rows) {
      if (!row.failure.empty()) continue;
      try {
        score(row, row.dir, gt, segments);
      } catch (const DataError& e) {
        row.failure = e.what();
      }
    }

    // The table: printed aligned, written as CSV.
    const std::vector<std::string> header{"model",
                                          "ate_m",
                                          "t_rel_pct",
                                          "r_rel_deg_100m",
                                          "loops_accepted",
                                          "loops_correct",
                                          "loops_wrong_pose",
                                          "segments_closed",
                                          "detect_ms_median",
                                          "detect_ms_p95",
                                          "query_ms_median",
                                          "signature_ms_median",
                                          "verify_ms_median",
                                          "status"};
    std::vector<std::vector<std::string>> cells{header};
    for (const Row& r : rows) {
      if (!r.failure.empty()) {
        std::vector<std::string> c(header.size(), "-");
        c.front() = r.name;
        c.back() = "failed: " + r.failure;
        cells.push_back(c);
        continue;
      }
      const RelativeErrors& rel = r.tm.relative;
      cells.push_back({r.name, fixed(r.tm.ate_rmse_m, 3), fixed(rel.valid ? rel.t_rel_pct : NAN, 3),
                       fixed(rel.valid ? rel.r_rel_deg_per_100m : NAN, 4), std::to_string(r.loops.accepted),
                       std::to_string(r.loops.correct),
                       r.pose_judged ? std::to_string(r.loops.wrong_pose) : "n/a",
                       std::to_string(r.loops.segmentsClosed()) + "/" + std::to_string(segments.size()),
                       fixed(r.detect_median, 2), fixed(r.detect_p95, 2), fixed(r.query_median, 2),
                       fixed(r.signature_median, 2), fixed(r.verify_median, 2), "ok"});
    }
    std::vector<size_t> width(header.size(), 0);
    for (const auto& line : cells)
      for (size_t i = 0; i + 1 < line.size(); ++i) width[i] = std::max(width[i], line[i].size());
    fs::create_directories(out);
    const fs::path csv_path = out / "summary.csv";
    std::ofstream csv(csv_path);
    for (const auto& line : cells) {
      for (size_t i = 0; i < line.size(); ++i) {
        csv << (i ? "," : "") << csvCell(line[i]);
        std::cout << line[i]
                  << (i + 1 == line.size() ? "\n" : std::string(width[i] - line[i].size() + 2, ' '));
      }
      csv << "\n";
    }
    if (!csv.flush()) throw DataError(csv_path.string() + ": cannot write");
    std::cout << "summary: " << csv_path.string() << "\n";

    if (runs > 1 || args.has("reference")) {
      std::vector<AccuracyRow> acc;
      for (const std::string& m : models) {
        std::vector<RunScore> scored;
        for (const Row& r : rows)
          if (r.model == m && r.failure.empty()) scored.push_back({r.tm, r.loops, r.lost_frames});
        if (!scored.empty()) acc.push_back(summarizeRuns(m, scored, static_cast<int>(segments.size())));
      }
      if (args.has("reference")) {
        const auto peer = scorePeerRuns(args.str("reference"), "peer:", gt, segments);
        acc.insert(acc.end(), peer.begin(), peer.end());
      }
      std::cout << "\naccuracy over " << runs << " run" << (runs == 1 ? "" : "s") << " per detector"
                << (args.has("reference") ? " and the peer's runs in " + args.str("reference")
                                          : std::string())
                << ":\n"
                << formatAccuracyTable(acc, false);
      const fs::path acc_path = out / "accuracy.csv";
      std::ofstream acc_csv(acc_path);
      acc_csv << formatAccuracyTable(acc, true);
      if (!acc_csv.flush()) throw DataError(acc_path.string() + ": cannot write");
      std::cout << "accuracy: " << acc_path.string() << "\n";
    }

    // One top view of every scored model over the ground truth they cover.
    std::vector<std::pair<std::string, std::vector<Pose3>>> aligned;
    int first = static_cast<int>(gt.size()), last = -1;
    for (const Row& r : rows) {
      if (!r.failure.empty()) continue;
      if (r.name != r.model && r.name != r.model + "/run-1") continue;  // one run of each model in the plot
      aligned.emplace_back(r.model + " (ATE " + fixed(r.tm.ate_rmse_m, 3) + " m)", r.aligned);
      first = std::min(first, r.first_frame);
      last = std::max(last, r.last_frame);
    }
    if (!aligned.empty()) {
      fs::path name = fs::absolute(seq).lexically_normal();
      if (name.filename().empty()) name = name.parent_path();  // "seq/" names "seq"
      const std::string title = "SLAM per loop detector on " + name.filename().string() + ", frames " +
                                std::to_string(first) + "-" + std::to_string(last);
      const fs::path png = out / "trajectories.png";
      writeTrajectoriesPlot(png.string(), title,
                            std::vector<Pose3>(gt.begin() + first, gt.begin() + last + 1), aligned);
      std::cout << "plot: " << png.string() << "\n";
    }

    std::string failed;
    int n_failed = 0;
    for (const Row& r : rows)
      if (!r.failure.empty()) failed += (n_failed++ ? ", " : "") + r.name;
    if (n_failed)
      throw DataError(std::to_string(n_failed) + " of " + std::to_string(rows.size()) +
                      " models failed: " + failed + " (see the status column)");
    return 0;
  });
}
