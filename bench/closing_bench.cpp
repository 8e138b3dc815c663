// Loop-closing timing benchmark: the figures the loop-closing issue sets goals for. Prints one markdown table
// of median / min / max over runs (never pass/fail) and writes the medians to $BINLOOP_BENCH_JSON
// (scripts/bench.sh sets .build/bench/closing.json).
//
// Rows and their data (synthetic, so that the numbers do not depend on a run of the SLAM):
// - verification of one candidate (loop/loop_verifier.h): two keyframes of 2000 stereo keypoints each,
//   1000 of them the same 3-D points seen from 1.5 m to the side and 8 degrees turned, the rest clutter;
//   brute force, and within ~100 coarse words (a shared point's word the same in both views, as hbow's
//   depth-2 cells give for most);
// - its step 1 alone (place/descriptor_block.h), the AVX-512 search and the plain loop, on random
// descriptors;
// - essential-graph optimisation (build + optim/pose_graph.h) of a loop of N keyframes driven round a
//   circle, each keyframe covisible (weight >= 100) with its 8 successors, as on rendered route 00 (1395
//   keyframes, 11138 edges), 0.5 % drift, one loop edge from the last keyframe to the first;
// - tracking's map replica (map/map_replica.h) taking the whole map after a loop correction, 1300 keyframes
//   of 2000 keypoints with 600 on points, as between two frames on rendered route 00.
// One thread (Ceres num_threads = 1).
//
//   bench_closing_bench [--runs N]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "../test/support/random_descriptors.h"
#include "../test/support/stereo_keypoint.h"
#include "bench_record.h"
#include "bench_stats.h"
#include "binloop/loop/essential_graph.h"
#include "binloop/loop/loop_verifier.h"
#include "binloop/map/map_replica.h"
#include "binloop/optim/pose_graph.h"
#include "binloop/place/descriptor_block.h"
#include "binloop/util/hash_random.h"

using namespace binloop;
using Clock = std::chrono::steady_clock;

namespace {

double ms(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

using binloop::bench::median;

struct Row {
  std::string name, goal, orbslam2;
  std::vector<double> runs;
};

// `words` gets a coarse word per keypoint as hbow's depth-2 cells would (~100): point i's is i % 100 in
// every view, clutter's a random one.
msg::KeyFrame keyframe(uint64_t id, const Pose3& T_w_c, const std::vector<Eigen::Vector3d>& pts,
                       const Descriptors& ds, HashRng& rng, std::vector<uint32_t>* words) {
  const StereoCamera cam = kittiCameraByName("kitti00");
  msg::KeyFrame kf;
  kf.id = kf.state.id = id;
  kf.camera = cam;
  kf.state.T_w_c = T_w_c;
  auto add = [&](const Eigen::Vector3d& p, const Desc256& d, uint32_t word) {
    if (test::addStereoKeypoint(kf, p, d)) words->push_back(word);
  };
  for (size_t i = 0; i < pts.size(); ++i) {
    add(T_w_c.inverse() * pts[i], test::flipBits(ds[i], 3, rng), static_cast<uint32_t>(i % 100));
  }
  while (kf.keypoints.size() < 2000) {
    Desc256 d;
    for (auto& w : d.w) w = rng.next();
    add(Eigen::Vector3d(rng.uniform(-10, 10), rng.uniform(-3, 2), rng.uniform(4, 40)), d,
        static_cast<uint32_t>(rng.below(100)));
  }
  return kf;
}

Row verification(bool by_words, int runs) {
  Row r{std::string("verification of one candidate (2000 x 2000 keypoints, 1000 shared), ") +
            (by_words ? "matching within ~100 words (hbow)" : "brute-force matching"),
        "<= 5 ms",
        "",
        {}};
  HashRng rng(3);
  std::vector<Eigen::Vector3d> pts;
  Descriptors ds;
  for (int i = 0; i < 1300; ++i) {
    pts.emplace_back(rng.uniform(-12, 12), rng.uniform(-3, 1.5), rng.uniform(4, 35));
    Desc256 d;
    for (auto& w : d.w) w = rng.next();
    ds.push_back(d);
  }
  Pose3 T_w_q = Pose3::Identity();
  T_w_q.linear() = Eigen::AngleAxisd(8 * M_PI / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T_w_q.translation() = Eigen::Vector3d(1.5, 0.1, 0.8);
  std::vector<uint32_t> cw, qw;
  const msg::KeyFrame c = keyframe(1, Pose3::Identity(), pts, ds, rng, &cw),
                      q = keyframe(2, T_w_q, pts, ds, rng, &qw);
  if (!by_words) cw.clear(), qw.clear();
  for (int i = 0; i < runs; ++i) {
    const auto t0 = Clock::now();
    const LoopVerification v = verifyLoop(q, c, {}, qw, cw);
    r.runs.push_back(ms(t0));
    if (i == 0)
      std::fprintf(stderr,
                   "closing_bench: verification steps (%s): %d matches in %.2f ms, RANSAC %.2f, refinement "
                   "%.2f, guided search + refinement %.2f\n",
                   by_words ? "words" : "brute force", v.matches, v.match_ms, v.ransac_ms, v.refine_ms,
                   v.guided_ms);
    if (!v.accepted)
      std::fprintf(stderr, "closing_bench: verification rejected the synthetic loop: %s\n", v.detail.c_str());
  }
  return r;
}

// Step 1 of verification alone, both ways: the eight-wide AVX-512 search where the CPU has it, the plain
// loop everywhere (what a CPU without AVX-512 VPOPCNTDQ runs).
Row bruteForce(bool wide, int runs) {
  Row r{
      std::string("step 1 alone: nearest + second of 2000 descriptors among 2000, ") +
          (wide ? (DescriptorBlock::wide() ? "AVX-512" : "AVX-512 (not on this CPU: plain)") : "plain loop"),
      "",
      "",
      {}};
  HashRng rng(4);
  Descriptors q(2000), c(2000);
  for (auto* set : {&q, &c})
    for (auto& d : *set)
      for (auto& w : d.w) w = rng.next();
  const DescriptorBlock block(c);
  for (int i = 0; i < runs; ++i) {
    const auto t0 = Clock::now();
    int sum = 0;
    for (const Desc256& d : q) sum += (wide ? block.nearest(d) : block.nearestPortable(d)).best;
    r.runs.push_back(ms(t0));
    if (sum == 0) std::fprintf(stderr, "closing_bench: no distance at all\n");  // keeps the loop
  }
  return r;
}

Row essentialGraph(int n, int runs) {
  Row r{"essential graph optimisation, " + std::to_string(n) + "-keyframe loop (8 covisible each)",
        n <= 300 ? "<= 100 ms" : "",
        n <= 300 ? "178 ms (loop of ~250 keyframes)" : "",
        {}};
  const double radius = 4.0 * n / (2 * M_PI);  // 4 m between keyframes
  std::vector<msg::KeyframeState> kfs;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * i / n;
    Pose3 truth = Pose3::Identity();
    truth.linear() = Eigen::AngleAxisd(-a, Eigen::Vector3d::UnitY()).toRotationMatrix();
    truth.translation() = Eigen::Vector3d(radius - radius * std::cos(a), 0, radius * std::sin(a));
    Pose3 drift = Pose3::Identity();
    drift.translation() = Eigen::Vector3d(0.005 * 4.0 * i, 0, 0);
    msg::KeyframeState s;
    s.id = static_cast<uint64_t>(i + 1);
    s.T_w_c = drift * truth;
    if (i > 0) s.parent = static_cast<uint64_t>(i);
    for (int k = 1; k <= 8 && i + k < n; ++k)
      s.covisible.push_back({static_cast<uint64_t>(i + 1 + k), 400u - 30u * k});
    kfs.push_back(s);
  }
  LoopEdge loop{static_cast<uint64_t>(n), 1, Pose3::Identity()};
  const Pose3 truth_last = Eigen::Translation3d(radius - radius * std::cos(2 * M_PI * (n - 1) / n), 0,
                                                radius * std::sin(2 * M_PI * (n - 1) / n)) *
                           Eigen::AngleAxisd(-2 * M_PI * (n - 1) / n, Eigen::Vector3d::UnitY());
  loop.T_query_candidate = truth_last.inverse();  // first keyframe's truth is the identity
  for (int i = 0; i < runs; ++i) {
    const auto t0 = Clock::now();
    const EssentialGraph g = buildEssentialGraph(kfs, {}, loop, {1});
    const PoseGraphResult res = optimizePoseGraph(g.nodes, g.edges);
    r.runs.push_back(ms(t0));
    if (i == 0)
      std::fprintf(stderr, "closing_bench: %d keyframes, %zu edges, %d iterations, loop chi2 %.1f -> %.2f\n",
                   n, g.edges.size(), res.iterations, res.initial_edge_chi2[g.new_loop_edge],
                   res.edge_chi2[g.new_loop_edge]);
  }
  return r;
}

// Tracking's map replica taking the whole map after a loop correction (every keyframe moved, every point
// moved, a few observations changed), as it does between two frames: on rendered route 00 at 1x, 1300
// keyframes, and one more tracking made meanwhile. Each keyframe has 2000 keypoints, 600 of them on points,
// each point seen by 5 consecutive keyframes (~156k points).
Row replicaCorrection(int n, int runs) {
  Row r{"tracking's map replica applies a whole-map correction, " + std::to_string(n) +
            " keyframes x 2000 keypoints (600 on points, each seen 5 times; a sixth lose 10)",
        "< 100 ms (one frame at 10 Hz)",
        "",
        {}};
  constexpr int kOnPoints = 600, kSeen = 5, kNewPerKeyframe = kOnPoints / kSeen;
  MapReplica base;
  msg::LocalMapUpdate u;
  u.correction = true;
  u.corrections_seen = 1;
  // Keyframe i (1-based id i + 1) and the kNewPerKeyframe points it makes.
  auto keyframe = [&](int i) {
    msg::KeyFrame kf;
    kf.id = kf.state.id = static_cast<uint64_t>(i + 1);
    kf.state.T_w_c.translation() = Eigen::Vector3d(0, 0, 1.0 * i);
    if (i > 0) kf.state.parent = static_cast<uint64_t>(i);
    kf.state.point_ids.assign(2000, kNoId);
    for (int j = 0; j < kNewPerKeyframe; ++j) {
      msg::MapPoint p;
      p.id = static_cast<uint64_t>(i) * kNewPerKeyframe + j + 1;
      p.p_w = Eigen::Vector3d(j % 20, j / 20, 1.0 * i + 10);
      p.reference = kf.id;
      kf.new_points.push_back(p);
    }
    return kf;
  };
  for (int i = 0; i < n; ++i) {
    msg::KeyFrame kf = keyframe(i);
    // Points made by this keyframe and the 4 before it, spread over the keypoints.
    for (int k = 0; k < kOnPoints; ++k) {
      const int maker = i - k / kNewPerKeyframe;
      if (maker < 0) continue;
      kf.state.point_ids[static_cast<size_t>(k) * 3] =
          static_cast<uint64_t>(maker) * kNewPerKeyframe + k % kNewPerKeyframe + 1;
    }
    base.add(kf);
    msg::KeyframeState moved = kf.state;
    moved.T_w_c.translation().x() += 0.01 * i;
    if (i % 6 == 0)  // a sixth of them lost 10 points (culled or fused across the loop)
      for (size_t k = 0; k < 30; k += 3) moved.point_ids[k] = kNoId;
    u.keyframes.push_back(moved);
    for (msg::MapPoint p : kf.new_points) {
      p.p_w.x() += 0.01 * i;
      u.points.push_back(p);
    }
  }
  // Made by tracking after the correction left mapping, sent nowhere yet: it moves with its parent.
  msg::KeyFrame unsent = keyframe(n);
  for (int j = 0; j < kNewPerKeyframe; ++j)
    unsent.state.point_ids[static_cast<size_t>(j) * 3] = unsent.new_points[j].id;
  base.add(unsent);
  for (int i = 0; i < runs; ++i) {
    MapReplica replica = base;
    const auto t0 = Clock::now();
    replica.apply(u, true);
    r.runs.push_back(ms(t0));
    if (i == 0)
      std::fprintf(stderr, "closing_bench: replica of %zu keyframes, %zu points\n", replica.keyframeCount(),
                   replica.pointCount());
  }
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  int runs = 7;
  for (int i = 1; i + 1 < argc; ++i)
    if (std::string(argv[i]) == "--runs") runs = std::max(1, std::atoi(argv[i + 1]));
  std::vector<Row> rows;
  rows.push_back(verification(false, runs * 3));
  rows.push_back(verification(true, runs * 3));
  rows.push_back(bruteForce(true, runs * 3));
  rows.push_back(bruteForce(false, runs * 3));
  rows.push_back(essentialGraph(250, runs));
  rows.push_back(essentialGraph(1400, std::max(1, runs / 2)));
  rows.push_back(replicaCorrection(1300, runs));
  // Global BA runs inside the SLAM (mapping.global_ba_after_loop); its time is in summary.json
  // (global_ba_ms).
  rows.push_back(
      {"global bundle adjustment, rendered route 06 (in the SLAM: run with mapping.global_ba_after_loop: 1)",
       "reported",
       "",
       {}});
  std::printf(
      "\nCPU: %s\n\n| measure | median ms | min | max | goal | ORB-SLAM2 (i7) | runs "
      "|\n|---|---|---|---|---|---|---|\n",
      bench::cpuModel().c_str());
  for (const Row& r : rows) {
    if (r.runs.empty()) {
      std::printf("| %s | in the SLAM: summary.json global_ba_ms | | | %s | %s | |\n", r.name.c_str(),
                  r.goal.c_str(), r.orbslam2.c_str());
      continue;
    }
    std::printf("| %s | %.2f | %.2f | %.2f | %s | %s | %zu |\n", r.name.c_str(), median(r.runs),
                *std::min_element(r.runs.begin(), r.runs.end()),
                *std::max_element(r.runs.begin(), r.runs.end()), r.goal.c_str(), r.orbslam2.c_str(),
                r.runs.size());
  }
  JsonObject record;
  record.add("cpu", bench::cpuModel()).add("verification_ms", median(rows[0].runs));
  record.add("verification_by_words_ms", median(rows[1].runs))
      .add("essential_graph_250_ms", median(rows[4].runs));
  record.add("essential_graph_1400_ms", median(rows[5].runs))
      .add("replica_correction_ms", median(rows[6].runs));
  bench::writeRecord(record, ".build/bench/closing.json");
  return 0;
}
