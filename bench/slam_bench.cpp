// SLAM timing benchmark: the figures the SLAM issue sets goals for, each next to its goal and ORB-SLAM2's
// reported figure (stereo KITTI, 2000 features, Intel i7-4790; ORB-SLAM2 reports means). Prints one markdown
// table of median / min / max over runs, never pass/fail, and writes the medians, the CPU model and the date
// to $BINLOOP_BENCH_JSON (scripts/bench.sh sets .build/bench/slam.json; default that path).
//
// Rows and their data:
// - ORB extraction, 2000 features, one 1241x376 image (pyramid included), and stereo matching of one pair:
//   the 11 real KITTI 00 pairs of ../shared/data/kitti/sample_00, one thread (cv::setNumThreads(1)).
// - tracking a frame end to end (FrameBuilder::build + Tracker::track = extraction + stereo + tracking),
//   local mapping per keyframe with local BA, and the lock-step pipeline's frames/s: SlamPipeline in
//   PipelineMode::kLockStep over a rendered stretch (default 300 frames), images decoded beforehand.
//   NOT one thread: FrameBuilder extracts the left and right images on two threads (std::async), as
//   ORB-SLAM2 does; pose optimisation and local BA run Ceres with num_threads = 1, and lock-step mapping
//   runs on the caller's thread. Tracking is also given on the real sample's frames 1-10, where the map
//   holds only the first few keyframes (so it is cheaper than in steady state).
// The rendered stretch is, in this order: the KITTI-layout folder given by --sequence or
// $BINLOOP_BENCH_SLAM_SEQUENCE (e.g. a `render` output); else rendered here, in memory, along
// ../shared/data/kitti/poses/06.txt (kitti04 camera, seed 1, the `render` tool's defaults: the frames
// `render --route .../06.txt --calib kitti04 --end <frames-1>` writes); else those rows are skipped with a
// message. About 1.5 minutes on the 2-core VM with the defaults, rendering (15-25 s) included.
//
//   bench_slam_bench [--sequence DIR] [--start N] [--frames N] [--runs N] [--config YAML] [--compare]
//                    [shared_data_dir]
//   --config times the tracker and local mapper with a SLAM config's settings instead of their defaults.
//   --compare adds the extractor comparison (binloop's ORB-SLAM-style extractor, OpenCV ORB, grid-spread
//   OpenCV ORB: count, coverage, stereo match rate) and the stereo matcher settings tables.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <opencv2/core/utility.hpp>
#include <opencv2/features2d.hpp>
#include <thread>

#include "bench_record.h"
#include "binloop/features/orb_slam_extractor.h"
#include "binloop/features/stereo_matcher.h"
#include "binloop/io/kitti_sequence.h"
#include "binloop/io/trajectory_io.h"
#include "binloop/pipeline/slam_config.h"
#include "binloop/pipeline/slam_pipeline.h"
#include "binloop/sim/stereo_renderer.h"
#include "binloop/sim/texture_bank.h"

using namespace binloop;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

// Runs of the cheap rows (real sample: a run is all 11 images) and, by default, of the rendered stretch.
constexpr int kRealRuns = 9;
constexpr int kStretchRuns = 5;

double ms(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

double mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? 0 : s / static_cast<double>(v.size());
}

// One row of the table: per-run values (each run's mean over its frames or keyframes, as ORB-SLAM2 reports
// means), summarised as median / min / max of the runs.
struct Result {
  Result(std::string n, std::string g, std::string o, std::string d)
      : name(std::move(n)), goal(std::move(g)), orbslam2(std::move(o)), data(std::move(d)) {}
  std::string name, goal, orbslam2, data;
  std::vector<double> runs;  // empty: skipped, `data` says why
  const char* fmt = "%.1f";
};

void printTable(const std::vector<Result>& rows) {
  std::printf("\n| measure | median | min | max | goal | ORB-SLAM2 (i7-4790) | data, threads |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  for (const Result& r : rows) {
    if (r.runs.empty()) {
      std::printf("| %s | skipped | | | %s | %s | %s |\n", r.name.c_str(), r.goal.c_str(), r.orbslam2.c_str(),
                  r.data.c_str());
      continue;
    }
    char med[32], lo[32], hi[32];
    std::snprintf(med, sizeof med, r.fmt, median(r.runs));
    std::snprintf(lo, sizeof lo, r.fmt, *std::min_element(r.runs.begin(), r.runs.end()));
    std::snprintf(hi, sizeof hi, r.fmt, *std::max_element(r.runs.begin(), r.runs.end()));
    std::printf("| %s | %s | %s | %s | %s | %s | %s, %zu runs |\n", r.name.c_str(), med, lo, hi,
                r.goal.c_str(), r.orbslam2.c_str(), r.data.c_str(), r.runs.size());
  }
}

// ---- rendered stretch: where its frames come from ----

struct Stretch {
  std::vector<StereoFrame> frames;
  StereoCamera cam;
  std::string source;    // for the table and the JSON
  std::string skipped;   // why there is no stretch (frames empty)
  double decode_ms = 0;  // mean time to read a frame's two PNGs (0 when rendered in memory)
};

Stretch loadStretch(const std::string& dir, size_t start, size_t n) {
  Stretch s;
  try {
    const auto seq = KittiSequence::open(dir);
    if (start >= seq.size())
      throw std::runtime_error("--start " + std::to_string(start) + " is past its " +
                               std::to_string(seq.size()) + " frames");
    const size_t end = std::min(seq.size(), start + n);
    s.cam = seq.camera();
    const auto t0 = Clock::now();
    for (size_t i = start; i < end; ++i) s.frames.push_back(seq.load(i));
    s.decode_ms = ms(t0) / static_cast<double>(end - start);
    s.source = dir + " frames " + std::to_string(start) + "-" + std::to_string(end - 1);
  } catch (const std::exception& e) {
    s.frames.clear();
    s.skipped = "cannot read sequence " + dir + ": " + e.what();
  }
  return s;
}

Stretch renderStretch(const std::string& shared, size_t start, size_t n) {
  Stretch s;
  const std::string route_file = shared + "/kitti/poses/06.txt";
  if (!fs::exists(route_file)) {
    s.skipped = "no sequence given (--sequence or $BINLOOP_BENCH_SLAM_SEQUENCE) and no " + route_file +
                " to render along";
    return s;
  }
  try {
    const auto t0 = Clock::now();
    const std::vector<Pose3> route = readKittiPoses(route_file);
    if (start + 1 >= route.size()) throw std::runtime_error("--start is past the route's end");
    const size_t end = std::min(route.size(), start + n);
    // As `render --route 06.txt --calib kitti04`: the world is built around the whole route, seed 1.
    auto bank = sim::TextureBank::build(sim::defaultTexturePhotos(), 1);
    const size_t photos = bank.photos_used;
    const auto world = sim::World::build(route, std::move(bank), {}, 1);
    s.cam = kittiCameraByName("kitti04");
    sim::StereoRenderer renderer(world, s.cam, {}, 1);
    std::fprintf(stderr, "rendering KITTI 06 frames %zu-%zu (%dx%d, %s)...\n", start, end - 1, s.cam.width,
                 s.cam.height,
                 photos ? (std::to_string(photos) + " photo textures").c_str() : "procedural textures");
    s.frames = sim::renderFrames(renderer, route, start, end - start);
    std::fprintf(stderr, "rendered %zu frames in %.0f s\n", s.frames.size(), ms(t0) / 1000);
    s.source = "KITTI 06 route rendered here, frames " + std::to_string(start) + "-" +
               std::to_string(end - 1) + (photos ? "" : ", procedural textures");
  } catch (const std::exception& e) {
    s.frames.clear();
    s.skipped = std::string("rendering failed: ") + e.what();
  }
  return s;
}

// ---- the pipeline over a stretch ----

struct PipelineRun {
  double fps = 0;
  double track_ms =
      0;  // mean extract + stereo + track of the frames tracked (state kOk), first frame excluded
  double extract_ms = 0, stereo_ms = 0, pose_ms = 0;  // its three parts (pose_ms: Tracker::track after build)
  double mapping_ms = 0;                              // mean per mapped keyframe
  double ba_ms = 0;
  double mapping_p95_ms = 0;
  int tracked = 0, lost = 0, keyframes = 0;
};

PipelineRun runPipeline(const std::vector<StereoFrame>& frames, const StereoCamera& cam,
                        const SlamConfig& config) {
  SlamPipeline slam(cam, config.tracker, config.mapper, PipelineMode::kLockStep);
  std::vector<msg::TrackedFrame> out;
  out.reserve(frames.size());
  const auto t0 = Clock::now();
  for (const StereoFrame& f : frames) out.push_back(slam.process(f));
  slam.finish();
  const double wall_ms = ms(t0);
  PipelineRun r;
  r.fps = 1000.0 * static_cast<double>(frames.size()) / wall_ms;
  std::vector<double> track, extract, stereo, pose, mapping, ba;
  for (size_t i = 0; i < out.size(); ++i) {
    const msg::TrackedFrame& tf = out[i];
    if (tf.state == msg::TrackingState::kLost) ++r.lost;
    if (i == 0 || tf.state != msg::TrackingState::kOk) continue;  // frame 0 only initialises the map
    ++r.tracked;
    track.push_back(tf.extract_ms + tf.stereo_ms + tf.track_ms);
    extract.push_back(tf.extract_ms);
    stereo.push_back(tf.stereo_ms);
    pose.push_back(tf.track_ms);
  }
  for (const auto& m : slam.mappingTimes()) {
    mapping.push_back(m.total_ms);
    ba.push_back(m.ba_ms);
  }
  r.keyframes = static_cast<int>(mapping.size());
  r.track_ms = mean(track);
  r.extract_ms = mean(extract);
  r.stereo_ms = mean(stereo);
  r.pose_ms = mean(pose);
  r.mapping_ms = mean(mapping);
  r.ba_ms = mean(ba);
  if (!mapping.empty()) {
    std::sort(mapping.begin(), mapping.end());
    r.mapping_p95_ms = mapping[static_cast<size_t>(0.95 * static_cast<double>(mapping.size() - 1))];
  }
  return r;
}

// "extraction a + stereo b + tracking c": medians over the runs of each part's mean.
std::string parts(const std::vector<PipelineRun>& runs) {
  std::vector<double> e, st, t;
  for (const auto& r : runs) e.push_back(r.extract_ms), st.push_back(r.stereo_ms), t.push_back(r.pose_ms);
  char buf[120];
  std::snprintf(buf, sizeof buf, "extraction %.1f + stereo %.1f + tracking %.1f ms", median(e), median(st),
                median(t));
  return buf;
}

// ---- --compare: extractors and stereo settings on the real sample ----

double gridCoverage(const std::vector<cv::KeyPoint>& kps, cv::Size size) {
  std::vector<char> cells(96, 0);
  for (const auto& k : kps)
    cells[std::min(5, static_cast<int>(k.pt.y * 6 / size.height)) * 16 +
          std::min(15, static_cast<int>(k.pt.x * 16 / size.width))] = 1;
  return std::count(cells.begin(), cells.end(), 1) / 96.0;
}

// The extractor every tool used before binloop had its own (retired from the core; kept here as the
// comparison's baseline): OpenCV ORB detecting 4x the budget (Harris score, FAST 20), then spread over a
// grid of 64-pixel cells, each cell giving its strongest keypoint, then its second, until the budget is met.
OrbFeatures gridSpreadOpenCvOrb(const cv::Mat& gray, int features) {
  constexpr int kCell = 64, kCandidates = 4;
  auto orb = cv::ORB::create(features * kCandidates, 1.2f, 8, 31, 0, 2, cv::ORB::HARRIS_SCORE, 31, 20);
  std::vector<cv::KeyPoint> kps;
  orb->detect(gray, kps);
  OrbFeatures out;
  if (kps.size() <= static_cast<size_t>(features)) {
    out.keypoints = std::move(kps);
  } else {
    const int cols = (gray.cols + kCell - 1) / kCell, rows = (gray.rows + kCell - 1) / kCell;
    std::vector<std::vector<cv::KeyPoint>> cells(static_cast<size_t>(cols * rows));
    for (const auto& k : kps)
      cells[static_cast<size_t>(std::clamp(static_cast<int>(k.pt.y) / kCell, 0, rows - 1) * cols +
                                std::clamp(static_cast<int>(k.pt.x) / kCell, 0, cols - 1))]
          .push_back(k);
    for (auto& c : cells)
      std::sort(c.begin(), c.end(), [](const cv::KeyPoint& a, const cv::KeyPoint& b) {
        if (a.response != b.response) return a.response > b.response;
        if (a.octave != b.octave) return a.octave < b.octave;
        return a.pt.y != b.pt.y ? a.pt.y < b.pt.y : a.pt.x < b.pt.x;
      });
    for (size_t rank = 0, any = 1; any && out.keypoints.size() < static_cast<size_t>(features); ++rank) {
      any = 0;
      for (const auto& c : cells)
        if (rank < c.size() && out.keypoints.size() < static_cast<size_t>(features)) {
          any = 1;
          out.keypoints.push_back(c[rank]);
        }
    }
  }
  cv::Mat desc;
  orb->compute(gray, out.keypoints, desc);
  out.descriptors = descriptorsFromMat(desc);
  return out;
}

// Extracts one image's features; fills `pyramid` when the extractor builds one the stereo matcher can read.
using Extractor = std::function<OrbFeatures(const cv::Mat&, ImagePyramid* pyramid)>;

struct Row {
  double extract_ms = 0, keypoints = 0, coverage = 0, stereo_rate = 0, stereo_ms = 0;
};

struct Side {
  OrbFeatures features;
  ImagePyramid pyramid;
};

Row measure(const Extractor& extract, const std::vector<StereoFrame>& frames, const StereoCamera& cam,
            const StereoMatchParams& sp = {}) {
  constexpr int kRuns = 5;
  std::vector<double> t_extract, t_stereo;
  std::vector<std::pair<Side, Side>> pairs(frames.size());
  for (int run = 0; run < kRuns; ++run)
    for (size_t i = 0; i < frames.size(); ++i) {
      Side l;
      const auto t0 = Clock::now();
      l.features = extract(frames[i].left, &l.pyramid);
      t_extract.push_back(ms(t0));
      if (run > 0) continue;
      Side r;
      r.features = extract(frames[i].right, &r.pyramid);
      // The matcher reads the levels the octaves name; OpenCV's own pyramid is internal, so build ours
      // (untimed) with OpenCV's factor and levels.
      if (l.pyramid.levels.empty()) l.pyramid = buildPyramid(frames[i].left, 8, 1.2f);
      if (r.pyramid.levels.empty()) r.pyramid = buildPyramid(frames[i].right, 8, 1.2f);
      pairs[i] = {std::move(l), std::move(r)};
    }
  Row row;
  for (int run = 0; run < kRuns; ++run)
    for (const auto& [l, r] : pairs) {
      const auto t0 = Clock::now();
      const StereoMatches m = matchStereo(l.features, l.pyramid, r.features, r.pyramid, cam, sp);
      t_stereo.push_back(ms(t0));
      if (run == 0)
        row.stereo_rate += static_cast<double>(m.matched) / std::max<size_t>(1, l.features.keypoints.size());
    }
  for (size_t i = 0; i < pairs.size(); ++i) {
    row.keypoints += pairs[i].first.features.keypoints.size();
    row.coverage += gridCoverage(pairs[i].first.features.keypoints, frames[i].left.size());
  }
  const double n = static_cast<double>(frames.size());
  row.keypoints /= n;
  row.coverage /= n;
  row.stereo_rate /= n;
  row.extract_ms = median(t_extract);
  row.stereo_ms = median(t_stereo);
  return row;
}

void compareExtractors(const std::vector<StereoFrame>& frames, const StereoCamera& cam) {
  const OrbSlamExtractor ours;  // 2000 features, 1.2, 8 levels
  auto opencv_orb = cv::ORB::create(2000, 1.2f, 8);
  const Extractor binloop_orbslam = [&](const cv::Mat& img, ImagePyramid* pyramid) {
    *pyramid = ours.pyramid(img);
    return ours.extract(*pyramid);
  };
  const Extractor opencv = [&](const cv::Mat& img, ImagePyramid*) {
    OrbFeatures f;
    cv::Mat desc;
    opencv_orb->detectAndCompute(img, cv::noArray(), f.keypoints, desc);
    f.descriptors = descriptorsFromMat(desc);
    return f;
  };
  const Extractor grid = [](const cv::Mat& img, ImagePyramid*) { return gridSpreadOpenCvOrb(img, 2000); };

  std::printf(
      "\nFeatures and stereo on the %zu real KITTI 00 pairs (1241x376), one thread, median of 5 runs x "
      "%zu images\n",
      frames.size(), frames.size());
  std::printf(
      "| extractor (2000 features, 1.2, 8 levels) | extraction ms | keypoints | 16x6 cells covered | stereo "
      "matched | stereo ms |\n|---|---|---|---|---|---|\n");
  for (const auto& [name, ex] : std::vector<std::pair<const char*, const Extractor*>>{
           {"(a) binloop OrbSlamExtractor, pyramid included", &binloop_orbslam},
           {"(b) OpenCV ORB", &opencv},
           {"(c) OpenCV ORB, 64-px grid spread (the retired extractOrb)", &grid}}) {
    const Row r = measure(*ex, frames, cam);
    std::printf("| %s | %.1f | %.0f | %.0f %% | %.0f %% | %.2f |\n", name, r.extract_ms, r.keypoints,
                100 * r.coverage, 100 * r.stereo_rate, r.stereo_ms);
  }

  std::printf(
      "\nStereo matcher settings on (a)'s features\n| setting | stereo matched | stereo ms "
      "|\n|---|---|---|\n");
  StereoMatchParams equiangular, centre;
  equiangular.fit = StereoMatchParams::SubPixelFit::kEquiangular;
  centre.centre_pixel_offset = true;
  for (const auto& [name, sp] :
       std::vector<std::pair<const char*, StereoMatchParams>>{{"default: mean offset, parabola", {}},
                                                              {"equiangular fit", equiangular},
                                                              {"ORB-SLAM2's centre-pixel offset", centre}}) {
    const Row r = measure(binloop_orbslam, frames, cam, sp);
    std::printf("| %s | %.0f %% | %.2f |\n", name, 100 * r.stereo_rate, r.stereo_ms);
  }
}

int usage(const char* msg) {
  if (msg) std::fprintf(stderr, "bench_slam_bench: %s\n", msg);
  std::fprintf(stderr,
               "usage: bench_slam_bench [--sequence DIR] [--start N] [--frames N] [--runs N] [--config YAML] "
               "[--compare] [shared_data_dir]\n");
  return msg ? 2 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  cv::setNumThreads(1);  // the goals are stated for one core; FrameBuilder still uses two threads (see top)
  std::string shared = BINLOOP_SHARED_DATA_DIR;
  std::string sequence_dir;
  if (const char* env = std::getenv("BINLOOP_BENCH_SLAM_SEQUENCE")) sequence_dir = env;
  size_t start = 0, n_frames = 300;
  int stretch_runs = kStretchRuns;
  bool compare = false;
  SlamConfig config;  // the parameter structs' defaults unless --config names a YAML (e.g. to time an option)
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--help" || a == "-h") return usage(nullptr);
    if (a == "--compare") {
      compare = true;
    } else if ((a == "--sequence" || a == "--start" || a == "--frames" || a == "--runs" || a == "--config") &&
               !has_value) {
      return usage((a + " needs a value").c_str());
    } else if (a == "--sequence") {
      sequence_dir = argv[++i];
    } else if (a == "--start") {
      start = std::strtoul(argv[++i], nullptr, 10);
    } else if (a == "--frames") {
      n_frames = std::strtoul(argv[++i], nullptr, 10);
    } else if (a == "--runs") {
      stretch_runs = std::atoi(argv[++i]);
    } else if (a == "--config") {
      try {
        config = loadSlamConfig(argv[++i]);
      } catch (const std::exception& e) {
        return usage(e.what());
      }
    } else if (!a.empty() && a[0] == '-') {
      return usage(("unknown option " + a).c_str());
    } else {
      shared = a;
    }
  }
  if (n_frames < 2 || stretch_runs < 1) return usage("--frames must be >= 2 and --runs >= 1");

  std::map<std::string, double> json;
  std::vector<Result> rows;

  // ---- the real KITTI 00 sample: extraction, stereo, tracking with a fresh map ----
  std::vector<StereoFrame> real;
  StereoCamera real_cam;
  std::string real_problem;
  try {
    const auto seq = KittiSequence::open(shared + "/kitti/sample_00");
    real_cam = seq.camera();
    for (size_t i = 0; i < seq.size(); ++i) real.push_back(seq.load(i));
  } catch (const std::exception& e) {
    real_problem = std::string("no KITTI sample: ") + e.what();
    std::printf("%s\n", real_problem.c_str());
  }
  Result extract_row{"ORB extraction, 2000 features, one 1241x376 image (ms)", "<= 20",
                     "24.8 (left and right on two threads)", real_problem};
  Result stereo_row{"stereo matching, one pair (ms)", "<= 10", "15.5", real_problem};
  Result track_real_row{"tracking a frame end to end: build + track, real frames (ms)", "<= 50", "49.5",
                        real_problem};
  double keypoints = 0, stereo_rate = 0;
  if (!real.empty()) {
    const OrbSlamExtractor ours;  // 2000 features, 1.2, 8 levels, as FrameBuilder's
    std::vector<std::pair<ImagePyramid, OrbFeatures>> left(real.size()), right(real.size());
    for (int run = 0; run < kRealRuns; ++run) {
      std::vector<double> t;
      for (size_t i = 0; i < real.size(); ++i) {
        const auto t0 = Clock::now();
        ImagePyramid p = ours.pyramid(real[i].left);
        OrbFeatures f = ours.extract(p);
        t.push_back(ms(t0));
        if (run == 0) {
          left[i] = {std::move(p), std::move(f)};
          right[i].first = ours.pyramid(real[i].right);
          right[i].second = ours.extract(right[i].first);
        }
      }
      extract_row.runs.push_back(mean(t));
    }
    for (int run = 0; run < kRealRuns; ++run) {
      std::vector<double> t;
      for (size_t i = 0; i < real.size(); ++i) {
        const auto t0 = Clock::now();
        const StereoMatches m =
            matchStereo(left[i].second, left[i].first, right[i].second, right[i].first, real_cam);
        t.push_back(ms(t0));
        if (run == 0) {
          keypoints +=
              static_cast<double>(left[i].second.keypoints.size()) / static_cast<double>(real.size());
          stereo_rate += m.matched / std::max(1.0, static_cast<double>(left[i].second.keypoints.size())) /
                         static_cast<double>(real.size());
        }
      }
      stereo_row.runs.push_back(mean(t));
    }
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "real KITTI 00 sample, %zu left images (%.0f keypoints), pyramid included, one thread",
                  real.size(), keypoints);
    extract_row.data = buf;
    std::snprintf(buf, sizeof buf, "real KITTI 00 sample, %zu pairs (%.0f %% matched), one thread",
                  real.size(), 100 * stereo_rate);
    stereo_row.data = buf;
    std::vector<PipelineRun> runs;
    for (int run = 0; run < kRealRuns; ++run) {
      runs.push_back(runPipeline(real, real_cam, config));
      track_real_row.runs.push_back(runs.back().track_ms);
    }
    const int tracked = runs.front().tracked;
    std::snprintf(
        buf, sizeof buf,
        "real KITTI 00 sample, frames 1-%zu (%d tracked; %d keyframes in all, so a small local map); %s; "
        "extraction on 2 threads",
        real.size() - 1, tracked, runs.front().keyframes, parts(runs).c_str());
    track_real_row.data = buf;
    if (tracked == 0) {
      track_real_row.runs.clear();
      track_real_row.data += ": none tracked";
    }
  }

  // ---- the rendered stretch: the pipeline in lock-step ----
  Stretch stretch;
  if (!sequence_dir.empty()) {
    std::fprintf(stderr, "loading %s...\n", sequence_dir.c_str());
    stretch = loadStretch(sequence_dir, start, n_frames);
  } else {
    stretch = renderStretch(shared, start, n_frames);
  }
  Result track_row{"tracking a frame end to end: build + track, rendered stretch (ms)", "<= 50", "49.5", ""};
  Result mapping_row{"local mapping with local BA, per keyframe (ms)", "<= 150", "~200", ""};
  Result fps_row{"lock-step pipeline, frames/s", "> 10", "n/a (real time at the camera's 10 Hz)", ""};
  std::string stretch_note;
  if (stretch.frames.empty()) {
    const std::string why = stretch.skipped + "; give a KITTI-layout folder with --sequence DIR";
    std::printf("rendered-stretch rows skipped: %s\n", why.c_str());
    track_row.data = mapping_row.data = fps_row.data = why;
  } else {
    std::vector<PipelineRun> runs;
    for (int run = 0; run < stretch_runs; ++run) {
      runs.push_back(runPipeline(stretch.frames, stretch.cam, config));
      const PipelineRun& r = runs.back();
      std::fprintf(stderr, "stretch run %d/%d: %.2f frames/s, %d tracked, %d lost, %d keyframes\n", run + 1,
                   stretch_runs, r.fps, r.tracked, r.lost, r.keyframes);
      track_row.runs.push_back(r.track_ms);
      mapping_row.runs.push_back(r.mapping_ms);
      fps_row.runs.push_back(r.fps);
    }
    const PipelineRun& r = runs.front();  // lock-step: every run tracks and maps the same (bit-identical)
    std::vector<double> ba, p95;
    for (const auto& x : runs) ba.push_back(x.ba_ms), p95.push_back(x.mapping_p95_ms);
    char buf[400];
    const std::string size = std::to_string(stretch.cam.width) + "x" + std::to_string(stretch.cam.height);
    std::snprintf(buf, sizeof buf, "%s (%s), %d of %zu frames tracked, %d lost; %s; extraction on 2 threads",
                  stretch.source.c_str(), size.c_str(), r.tracked, stretch.frames.size(), r.lost,
                  parts(runs).c_str());
    track_row.data = buf;
    std::snprintf(buf, sizeof buf,
                  "same stretch, %d keyframes; local BA %.1f ms of it, p95 %.0f ms (medians); one thread",
                  r.keyframes, median(ba), median(p95));
    mapping_row.data = buf;
    const std::string decode = stretch.decode_ms > 0
                                   ? " (PNG decoding, " +
                                         std::to_string(static_cast<int>(stretch.decode_ms + 0.5)) +
                                         " ms/frame here, not included)"
                                   : "";
    std::snprintf(
        buf, sizeof buf,
        "SlamPipeline kLockStep over the same %zu frames, images in memory%s; tracking's 2 extraction "
        "threads, mapping on the caller's",
        stretch.frames.size(), decode.c_str());
    fps_row.data = buf;
    fps_row.fmt = "%.2f";
    json["local_ba_per_keyframe_ms_median"] = median(ba);
    json["mapping_per_keyframe_ms_p95_median"] = median(p95);
    json["stretch_frames"] = static_cast<double>(stretch.frames.size());
    json["stretch_tracked"] = r.tracked;
    json["stretch_lost"] = r.lost;
    json["stretch_keyframes"] = r.keyframes;
  }

  std::printf(
      "\nSLAM timings (SLAM issue goals), median / min / max over runs; a run's value is its mean over "
      "frames or keyframes, as ORB-SLAM2 reports means (stereo KITTI, i7-4790)\n");
  rows = {extract_row, stereo_row, track_real_row, track_row, mapping_row, fps_row};
  printTable(rows);

  const std::pair<const char*, const Result*> keys[] = {
      {"orb_extract_ms_median", &extract_row},          {"stereo_ms_median", &stereo_row},
      {"track_frame_real_ms_median", &track_real_row},  {"track_frame_ms_median", &track_row},
      {"mapping_per_keyframe_ms_median", &mapping_row}, {"pipeline_fps_median", &fps_row}};
  for (const auto& [key, row] : keys)
    if (!row->runs.empty()) json[key] = median(row->runs);
  if (!real.empty()) {
    json["keypoints_per_image"] = keypoints;
    json["stereo_match_rate"] = stereo_rate;
  }

  if (compare && !real.empty()) compareExtractors(real, real_cam);

  JsonObject record = bench::machineRecord();
  record.add("runs_real", kRealRuns).add("runs_stretch", stretch_runs);
  record.add("stretch", stretch.frames.empty() ? "skipped: " + stretch.skipped : stretch.source);
  for (const auto& [k, v] : json) record.add(k, v);
  const std::string path = bench::writeRecord(record, ".build/bench/slam.json");
  std::printf("\nwrote %s\n", path.c_str());
  return 0;
}
