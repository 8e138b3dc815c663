#include "binloop/pipeline/loop_log.h"

#include <fstream>
#include <sstream>

#include "binloop/eval/slam_evaluation.h"
#include "binloop/io/data_error.h"

namespace binloop {

namespace {

constexpr const char* kHeader =
    "keyframe,frame,model,shadow,status,candidates,consistency,accepted_candidate,closure,match_frame,"
    "matches,"
    "inliers,correction_m,drift_bound_m,residual_ratio,detect_ms,verify_ms,optimize_ms,correction_ms,switch_"
    "ms,"
    "detail,query_to_match,gt_error_m,gt_error_deg";
constexpr size_t kFields = 24;
constexpr size_t kFieldsBefore = 21;  // loops.csv before query_to_match and the ground-truth errors

std::string quoted(const std::string& s) {
  std::string o = "\"";
  for (char c : s) o += c == '"' ? std::string("\"\"") : std::string(1, c);
  return o + "\"";
}

// Fields of one CSV line; quotes as written by quoted().
std::vector<std::string> fields(const std::string& line) {
  std::vector<std::string> f(1);
  bool in = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (in && c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
      f.back() += '"', ++i;
    } else if (c == '"') {
      in = !in;
    } else if (c == ',' && !in) {
      f.emplace_back();
    } else {
      f.back() += c;
    }
  }
  return f;
}

// T_query_match as "tx ty tz qw qx qy qz" (metres; unit quaternion).
std::string poseText(const Pose3& T) {
  const Eigen::Quaterniond q(T.linear());
  std::ostringstream o;
  o.precision(9);
  o << T.translation().x() << " " << T.translation().y() << " " << T.translation().z() << " " << q.w() << " "
    << q.x() << " " << q.y() << " " << q.z();
  return o.str();
}

Pose3 parsePose(const std::string& text) {
  std::istringstream in(text);
  double v[7];
  for (double& x : v)
    if (!(in >> x)) throw std::invalid_argument("pose");
  Pose3 T = Pose3::Identity();
  T.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
  const Eigen::Quaterniond q(v[3], v[4], v[5], v[6]);
  if (!(q.norm() > 0.5 && q.norm() < 1.5)) throw std::invalid_argument("quaternion");
  T.linear() = q.normalized().toRotationMatrix();
  return T;
}

void row(std::ostream& o, const msg::LoopCandidates* q, const msg::LoopClosure* c, double correction_ms,
         double switch_ms, const std::vector<Pose3>* gt) {
  if (q) {
    std::string cands;
    for (size_t i = 0; i < q->candidates.size() && i < 5; ++i) {
      cands += (i ? " " : "") + std::to_string(counterOf(q->candidates[i].id)) + ":" +
               std::to_string(q->candidates[i].score);
    }
    o << counterOf(q->query) << "," << q->query_frame << "," << q->model << "," << q->shadow << ","
      << q->status << "," << quoted(cands) << "," << q->consistency << ","
      << (q->accepted == kNoId ? std::string() : std::to_string(counterOf(q->accepted))) << ",";
  } else {
    o << counterOf(c->query) << "," << c->query_frame << "," << c->model << ",0,,\"\",,,";
  }
  if (c) {
    o << msg::loopStatusName(c->status) << "," << c->match_frame << "," << c->matches << "," << c->inliers
      << "," << c->correction_m << "," << c->drift_bound_m << "," << c->residual_ratio << ",";
  } else {
    o << ",,,,,,,";
  }
  o << (q ? q->total_ms : 0) << "," << (c ? c->verify_ms : 0) << "," << (c ? c->optimize_ms : 0) << ","
    << correction_ms << "," << switch_ms << ","
    << quoted(c   ? c->detail
              : q ? q->detail
                  : "")
    << ",";
  // A verified pair's relative pose, and its error against the ground truth when the frames have one.
  const bool verified = c && c->inliers > 0;
  o << (verified ? poseText(c->T_query_match) : std::string()) << ",";
  const auto n = static_cast<uint64_t>(gt ? gt->size() : 0);
  if (verified && c->query_frame < n && c->match_frame < n) {
    const LoopPoseError e = loopPoseError(static_cast<int>(c->query_frame), static_cast<int>(c->match_frame),
                                          c->T_query_match, *gt);
    o << e.translation_m << "," << e.rotation_deg << "\n";
  } else {
    o << ",\n";
  }
}

}  // namespace

void writeLoopLog(const std::string& path, const std::vector<SlamPipeline::LoopLogEntry>& log,
                  const std::vector<Pose3>* ground_truth) {
  std::ofstream o(path);
  if (!o) throw DataError("cannot write " + path);
  o << kHeader << "\n";
  for (const auto& e : log) {
    const msg::LoopClosure* own = nullptr;
    for (const auto& c : e.closures)
      if (e.active && c->query == e.active->query && !own) own = c.get();
    if (e.active) row(o, e.active.get(), own, e.correction_ms, e.switch_ms, ground_truth);
    for (const auto& c : e.closures)
      if (c.get() != own) row(o, nullptr, c.get(), 0, 0, ground_truth);
    for (const auto& s : e.shadow) row(o, s.get(), nullptr, 0, 0, ground_truth);
  }
}

std::vector<LoggedLoop> readLoopLog(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw DataError(path + ": cannot open");
  std::string line;
  const std::string header(kHeader);
  const std::string old_header = header.substr(0, header.find(",query_to_match"));
  if (!std::getline(in, line) || (line != header && line != old_header))
    throw DataError(path + ": not a loops.csv (header differs)");
  const size_t fields_expected = line == header ? kFields : kFieldsBefore;
  std::vector<LoggedLoop> out;
  size_t n = 1;
  while (std::getline(in, line)) {
    ++n;
    const std::vector<std::string> f = fields(line);
    if (f.size() != fields_expected) {
      throw dataError(path, static_cast<int>(n),
                      std::to_string(f.size()) + " fields, expected " + std::to_string(fields_expected));
    }
    if (f[8].empty()) continue;  // no closure on this row
    LoggedLoop l;
    try {
      l.status = msg::parseLoopStatus(f[8]);
    } catch (const std::invalid_argument& e) {
      throw dataError(path, static_cast<int>(n), e.what());
    }
    try {
      l.model = f[2];
      l.query_frame = std::stoull(f[1]);
      l.match_frame = std::stoull(f[9]);
      l.inliers = std::stoi(f[11]);
      l.correction_m = std::stod(f[12]);
      if (f.size() > kFieldsBefore && !f[21].empty()) {
        l.T_query_match = parsePose(f[21]);
        l.has_pose = true;
      }
      out.push_back(l);
    } catch (const std::exception&) {
      throw dataError(path, static_cast<int>(n), "a number field is not a number");
    }
  }
  return out;
}

}  // namespace binloop
