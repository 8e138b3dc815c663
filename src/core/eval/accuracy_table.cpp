#include "binloop/eval/accuracy_table.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "binloop/io/data_error.h"
#include "binloop/io/trajectory_io.h"
#include "binloop/util/fixed_decimals.h"
#include "binloop/util/median.h"

namespace binloop {

namespace {

double minOf(const std::vector<double>& v) {
  double m = NAN;
  for (double x : v)
    if (std::isfinite(x) && !(x >= m)) m = x;
  return m;
}

double maxOf(const std::vector<double>& v) {
  double m = NAN;
  for (double x : v)
    if (std::isfinite(x) && !(x <= m)) m = x;
  return m;
}

std::string cell(double v, int decimals) { return std::isfinite(v) ? fixedDecimals(v, decimals) : "n/a"; }

// "loops-2" -> "loops"; a name without a numeric "-N" suffix is its own group.
std::string groupOf(const std::string& name) {
  const size_t dash = name.rfind('-');
  if (dash == std::string::npos || dash + 1 == name.size()) return name;
  for (size_t i = dash + 1; i < name.size(); ++i)
    if (name[i] < '0' || name[i] > '9') return name;
  return name.substr(0, dash);
}

// Frames whose state is not 2 (tracked) in ORB-SLAM2's TrackingTimes.txt.
int peerLostFrames(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) return 0;
  std::string line;
  int lost = 0, n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    double frame, stamp, seconds;
    int state;
    if (!(s >> frame >> stamp >> seconds >> state))
      throw dataError(path.string(), n, "expected 'frame stamp seconds state'");
    lost += state != 2;
  }
  return lost;
}

}  // namespace

AccuracyRow summarizeRuns(const std::string& name, const std::vector<RunScore>& runs, int segments) {
  if (runs.empty()) throw DataError(name + ": no run to sum up");
  AccuracyRow r;
  r.name = name;
  r.runs = static_cast<int>(runs.size());
  r.segments = segments;
  std::vector<double> ate, t, rr, loops;
  std::vector<int> closed_in(static_cast<size_t>(segments), 0);
  for (const RunScore& s : runs) {
    ate.push_back(s.metrics.ate_rmse_m);
    t.push_back(s.metrics.relative.valid ? s.metrics.relative.t_rel_pct : NAN);
    rr.push_back(s.metrics.relative.valid ? s.metrics.relative.r_rel_deg_per_100m : NAN);
    loops.push_back(s.loops.accepted);
    r.loops_wrong += s.loops.accepted - s.loops.correct;
    r.lost_max = std::max(r.lost_max, s.lost_frames);
    for (size_t i = 0; i < s.loops.closed.size() && i < closed_in.size(); ++i)
      closed_in[i] += s.loops.closed[i];
  }
  r.ate_median = median(ate);
  r.ate_min = minOf(ate);
  r.ate_max = maxOf(ate);
  r.t_rel_median = median(t);
  r.t_rel_min = minOf(t);
  r.t_rel_max = maxOf(t);
  r.r_rel_median = median(rr);
  r.loops_median = median(loops);
  for (int c : closed_in) r.segments_every_run += c == r.runs;
  return r;
}

std::vector<AccuracyRow> scorePeerRuns(const std::string& dir, const std::string& prefix,
                                       const std::vector<Pose3>& gt,
                                       const std::vector<RevisitSegment>& segments) {
  namespace fs = std::filesystem;
  if (!fs::is_directory(dir)) throw DataError(dir + ": no such folder");
  std::vector<fs::path> folders;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.is_directory() && fs::exists(e.path() / "CameraTrajectory.txt")) folders.push_back(e.path());
  if (folders.empty()) throw DataError(dir + ": no run folder with a CameraTrajectory.txt");
  std::sort(folders.begin(), folders.end());
  std::map<std::string, std::vector<RunScore>> groups;
  std::map<std::string, int> unjudged;
  std::vector<std::string> order;
  for (const fs::path& f : folders) {
    const std::string traj = (f / "CameraTrajectory.txt").string();
    RunScore s;
    s.metrics = evaluateTrajectory(matchByFrameIndex(gt, readEstimateFile(traj), traj));
    std::vector<std::pair<int, int>> loops;
    if (fs::exists(f / "loops.txt")) loops = readIndexPairs((f / "loops.txt").string());
    s.loops = scoreLoops(loops, gt, segments);
    s.lost_frames = peerLostFrames(f / "TrackingTimes.txt");
    const std::string g = groupOf(f.filename().string());
    if (!groups.count(g)) order.push_back(g);
    groups[g].push_back(s);
    unjudged[g] += !loops.empty();
  }
  std::vector<AccuracyRow> rows;
  for (const std::string& g : order) {
    rows.push_back(summarizeRuns(prefix + g, groups[g], static_cast<int>(segments.size())));
    rows.back().wrong_unjudged_pose = unjudged[g];
  }
  return rows;
}

std::string formatAccuracyTable(const std::vector<AccuracyRow>& rows, bool csv) {
  const std::vector<std::string> header{"system",
                                        "runs",
                                        "ate_m_median",
                                        "ate_m_min",
                                        "ate_m_max",
                                        "ate_spread",
                                        "t_rel_pct_median",
                                        "t_rel_pct_min",
                                        "t_rel_pct_max",
                                        "r_rel_deg_100m_median",
                                        "loops_median",
                                        "loops_wrong",
                                        "segments_closed_every_run",
                                        "lost_frames_max"};
  std::vector<std::vector<std::string>> cells{header};
  for (const AccuracyRow& r : rows) {
    cells.push_back({r.name, std::to_string(r.runs), cell(r.ate_median, 3), cell(r.ate_min, 3),
                     cell(r.ate_max, 3), cell(r.spread(), 2), cell(r.t_rel_median, 3), cell(r.t_rel_min, 3),
                     cell(r.t_rel_max, 3), cell(r.r_rel_median, 3), cell(r.loops_median, 1),
                     std::to_string(r.loops_wrong) + (r.wrong_unjudged_pose ? " (distance only)" : ""),
                     std::to_string(r.segments_every_run) + "/" + std::to_string(r.segments),
                     std::to_string(r.lost_max)});
  }
  std::vector<size_t> width(header.size(), 0);
  for (const auto& line : cells)
    for (size_t i = 0; i < line.size(); ++i) width[i] = std::max(width[i], line[i].size());
  std::ostringstream o;
  for (const auto& line : cells) {
    for (size_t i = 0; i < line.size(); ++i) {
      if (csv) {
        o << (i ? "," : "") << (line[i].find(',') != std::string::npos ? "\"" + line[i] + "\"" : line[i]);
      } else {
        o << line[i] << (i + 1 == line.size() ? "" : std::string(width[i] - line[i].size() + 2, ' '));
      }
    }
    o << "\n";
  }
  return o.str();
}

}  // namespace binloop
