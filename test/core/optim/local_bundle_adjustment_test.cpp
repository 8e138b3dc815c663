#include "binloop/optim/local_bundle_adjustment.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <limits>

#include "optim_test_scene.h"
#include "support/test_support.h"

using namespace binloop;
using namespace binloop::test;

namespace {

// A KITTI-like window: keyframes 1.5 m apart driving forward with a gentle left turn; the first
// `fixed` keyframes are held still (ORB-SLAM2's fixed keyframes see the local points but are not local).
// Each point is born in one keyframe at 3-45 m and tracked over the next 2-8 keyframes where it stays in
// the image. `truth` holds the exact poses and points, `problem` the same with perturbed starting values
// for the free keyframes and the points; both hold the same (noisy) measurements.
struct Window {
  StereoCamera cam = kitti();
  BaProblem truth, problem;
  std::vector<bool> gross;  // per observation: a planted wrong association
};

struct WindowSpec {
  int keyframes = 20, fixed = 10, points = 1500;
  int max_track = 8;  // keyframes a point is tracked over after its birth (2 to max_track)
  double outlier_share = 0.05, pixel_sigma = 0.5;
  double pose_deg = 0.5, pose_m = 0.1, point_m = 0.1;  // perturbation of the starting values
  uint64_t seed = 1;
};

WindowSpec spec(int points, uint64_t seed, double outlier_share = 0.05) {
  WindowSpec s;
  s.points = points;
  s.seed = seed;
  s.outlier_share = outlier_share;
  return s;
}

Window makeWindow(const WindowSpec& s) {
  Window w;
  HashRng rng(s.seed);
  for (int i = 0; i < s.keyframes; ++i) {
    Pose3 T_w_c = Pose3::Identity();
    T_w_c.linear() = Eigen::AngleAxisd(-1.0 * i * kPi / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
    T_w_c.translation() = Eigen::Vector3d(0.02 * i * i, 0.01 * i, 1.5 * i);
    w.truth.keyframes.push_back({1000 + static_cast<uint64_t>(i), T_w_c.inverse(), i < s.fixed});
  }
  while (static_cast<int>(w.truth.points.size()) < s.points) {
    const int birth = rng.below(s.keyframes), track = 2 + rng.below(s.max_track - 1);
    const Eigen::Vector3d p_w =
        backProject(w.cam, w.truth.keyframes[birth].T_c_w, rng.uniform(0, w.cam.width),
                    rng.uniform(0, w.cam.height), rng.uniform(3, 45));
    std::vector<BaObservation> obs;
    std::vector<bool> gross;
    const size_t j = w.truth.points.size();
    for (int i = birth; i < std::min(s.keyframes, birth + track); ++i) {
      Measurement m = measure(w.cam, w.truth.keyframes[i].T_c_w * p_w, s.pixel_sigma, true, rng);
      if (!m.visible) continue;
      const bool bad = rng.chance(s.outlier_share);
      if (bad) corrupt(m, rng);
      obs.push_back({static_cast<size_t>(i), j, m.uv, m.u_right, m.inv_sigma2});
      gross.push_back(bad);
    }
    if (obs.size() < 2) continue;
    w.truth.points.push_back({5000 + j, p_w});
    w.truth.observations.insert(w.truth.observations.end(), obs.begin(), obs.end());
    w.gross.insert(w.gross.end(), gross.begin(), gross.end());
  }
  w.problem = w.truth;
  for (BaKeyframe& kf : w.problem.keyframes)
    if (!kf.fixed) kf.T_c_w = perturb(kf.T_c_w, s.pose_deg, s.pose_m, rng);
  for (BaPoint& p : w.problem.points)
    p.p_w += s.point_m * Eigen::Vector3d(rng.normal(), rng.normal(), rng.normal());
  return w;
}

struct Errors {
  double centre_m = 0, rotation_deg = 0;  // mean over the free keyframes
  double point_m = 0;                     // median over the points
};

Errors errors(const Window& w, const std::vector<BaRefinedKeyframe>& kfs,
              const std::vector<BaPoint>& points) {
  Errors e;
  for (const BaRefinedKeyframe& k : kfs) {
    e.centre_m += centreError(k.T_c_w, w.truth.keyframes[k.index].T_c_w) / kfs.size();
    e.rotation_deg += rotationErrorDeg(k.T_c_w, w.truth.keyframes[k.index].T_c_w) / kfs.size();
  }
  std::vector<double> d;
  for (size_t j = 0; j < points.size(); ++j) d.push_back((points[j].p_w - w.truth.points[j].p_w).norm());
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  e.point_m = d[d.size() / 2];
  return e;
}

std::vector<BaRefinedKeyframe> freeKeyframes(const BaProblem& pb) {
  std::vector<BaRefinedKeyframe> out;
  for (size_t i = 0; i < pb.keyframes.size(); ++i)
    if (!pb.keyframes[i].fixed) out.push_back({i, pb.keyframes[i].id, pb.keyframes[i].T_c_w});
  return out;
}

// How the outlier flags compare with the planted outliers. A point with a wrong association is pulled by
// it in the robust stage, so its good observations may be flagged too ("tainted" points); on the other
// points a flag is a false alarm.
struct FlagStats {
  int planted = 0, missed = 0, clean = 0, clean_flagged = 0;
};

FlagStats flagStats(const Window& w, const LocalBaResult& r) {
  const BaProblem& pb = w.problem;
  std::vector<bool> tainted(pb.points.size());
  for (size_t i = 0; i < r.outlier.size(); ++i)
    if (w.gross[i]) tainted[pb.observations[i].point] = true;
  FlagStats f;
  for (size_t i = 0; i < r.outlier.size(); ++i) {
    f.planted += w.gross[i];
    f.missed += w.gross[i] && !r.outlier[i];
    if (tainted[pb.observations[i].point]) continue;
    ++f.clean;
    f.clean_flagged += r.outlier[i];
  }
  return f;
}

bool sameBits(const Pose3& a, const Pose3& b) {
  return std::memcmp(a.matrix().data(), b.matrix().data(), 16 * sizeof(double)) == 0;
}

}  // namespace

// With 0.5 px noise the truth is not the least-squares optimum: the points' own uncertainty (far, mono,
// forward motion) is above the 0.1 m perturbation. So the poses are checked against the truth, down to the
// noise floor (about 5 mm and 0.015 deg here), and everything against the optimum that the same
// adjustment reaches when started at the truth.
TEST(LocalBundleAdjustment, ShrinksTheErrorKeepsFixedKeyframesAndFlagsGrossOutliers) {
  const Window w = makeWindow({});
  const BaProblem& pb = w.problem;
  int stereo = 0;
  for (const BaObservation& o : pb.observations) stereo += o.u_right >= 0;
  ASSERT_GT(stereo, 0.2 * pb.observations.size());
  ASSERT_LT(stereo, 0.8 * pb.observations.size());

  const LocalBaResult r = localBundleAdjustment(w.cam, pb);
  const Errors before = errors(w, freeKeyframes(pb), pb.points), after = errors(w, r.keyframes, r.points);
  EXPECT_LT(after.centre_m, 0.1 * before.centre_m);
  EXPECT_LT(after.rotation_deg, 0.1 * before.rotation_deg);

  const LocalBaResult best = localBundleAdjustment(w.cam, w.truth);
  Window optimum = w;
  for (const BaRefinedKeyframe& k : best.keyframes) optimum.truth.keyframes[k.index].T_c_w = k.T_c_w;
  optimum.truth.points = best.points;
  const Errors start = errors(optimum, freeKeyframes(pb), pb.points),
               end = errors(optimum, r.keyframes, r.points);
  EXPECT_LT(end.centre_m, 0.02 * start.centre_m);
  EXPECT_LT(end.rotation_deg, 0.02 * start.rotation_deg);
  EXPECT_LT(end.point_m, 0.02 * start.point_m);

  // Exactly the free keyframes come back, in input order. The fixed ones hold the window's gauge: had they
  // moved, the free ones could not have landed on the truth.
  ASSERT_EQ(r.keyframes.size(), 10u);
  for (size_t i = 0; i < r.keyframes.size(); ++i) {
    EXPECT_EQ(r.keyframes[i].index, 10 + i);
    EXPECT_EQ(r.keyframes[i].id, pb.keyframes[10 + i].id);
  }
  ASSERT_EQ(r.points.size(), pb.points.size());
  for (size_t j = 0; j < r.points.size(); ++j) ASSERT_EQ(r.points[j].id, pb.points[j].id);

  // Every planted outlier is flagged, and (almost) no observation of a point without one.
  ASSERT_EQ(r.outlier.size(), pb.observations.size());
  const FlagStats f = flagStats(w, r);
  ASSERT_GT(f.planted, 100);
  EXPECT_EQ(f.missed, 0);
  EXPECT_LE(f.clean_flagged, 0.005 * f.clean);
  EXPECT_LE(r.summary.num_outliers, 2 * f.planted);
  EXPECT_EQ(r.summary.num_outliers, static_cast<int>(std::count(r.outlier.begin(), r.outlier.end(), true)));
  EXPECT_LT(r.summary.final_cost, 0.01 * r.summary.initial_cost);
  EXPECT_GT(r.summary.iterations, 5);
  EXPECT_LE(r.summary.iterations, 15);
  EXPECT_FALSE(r.aborted);
  EXPECT_GT(r.summary.time_s, 0);
}

// Without pixel noise the truth is the optimum: poses and points land on it.
TEST(LocalBundleAdjustment, NoiseFreeWindowLandsOnTheTruth) {
  WindowSpec s = spec(800, 8);
  s.pixel_sigma = 0;
  const Window w = makeWindow(s);
  const LocalBaResult r = localBundleAdjustment(w.cam, w.problem);
  const Errors before = errors(w, freeKeyframes(w.problem), w.problem.points),
               after = errors(w, r.keyframes, r.points);
  EXPECT_LT(after.centre_m, 1e-4 * before.centre_m);
  EXPECT_LT(after.rotation_deg, 1e-4 * before.rotation_deg);
  EXPECT_LT(after.point_m, 1e-4 * before.point_m);
  const FlagStats f = flagStats(w, r);
  EXPECT_GT(f.planted, 50);
  EXPECT_EQ(f.missed, 0);
  EXPECT_EQ(f.clean_flagged, 0);
}

// A fixed keyframe holds still even when its pose is wrong: its observations cannot be fit and end up
// outliers. Set free, the same keyframe is pulled back onto the truth and its observations fit.
TEST(LocalBundleAdjustment, FixedKeyframesDoNotMove) {
  Window w = makeWindow(spec(800, 9, 0.0));
  HashRng rng(9);
  w.problem.keyframes[0].T_c_w = perturb(w.truth.keyframes[0].T_c_w, 2, 0.3, rng);
  auto share_flagged = [&](const LocalBaResult& r) {
    int seen = 0, flagged = 0;
    for (size_t i = 0; i < r.outlier.size(); ++i) {
      if (w.problem.observations[i].keyframe != 0) continue;
      ++seen;
      flagged += r.outlier[i];
    }
    return static_cast<double>(flagged) / seen;
  };
  const LocalBaResult held = localBundleAdjustment(w.cam, w.problem);
  for (const BaRefinedKeyframe& k : held.keyframes) EXPECT_NE(k.index, 0u);
  EXPECT_GT(share_flagged(held), 0.75);  // some far points can follow the wrong pose

  w.problem.keyframes[0].fixed = false;
  const LocalBaResult freed = localBundleAdjustment(w.cam, w.problem);
  ASSERT_EQ(freed.keyframes.front().index, 0u);
  EXPECT_LT(centreError(freed.keyframes.front().T_c_w, w.truth.keyframes[0].T_c_w), 0.01);
  EXPECT_LT(share_flagged(freed), 0.05);
}

// Two groups of keyframes that share no point: the one with a fixed keyframe keeps it as its only anchor,
// the other gets its oldest keyframe (lowest id, wherever it stands in the list) held.
TEST(LocalBundleAdjustment, EachGroupWithoutAnAnchorHoldsItsOldestKeyframe) {
  BaProblem p;
  for (uint64_t id : {7, 3, 5, 9, 4}) p.keyframes.push_back({id, Pose3::Identity(), false});
  p.keyframes[0].fixed = true;  // keyframe 7 anchors the group {7, 3}
  for (uint64_t i = 0; i < 3; ++i) p.points.push_back({i, Eigen::Vector3d(0, 0, 10)});
  auto see = [&](size_t kf, size_t pt) { p.observations.push_back({kf, pt, {1, 1}, -1, 1}); };
  see(0, 0), see(1, 0);             // 7 and 3 share point 0
  see(2, 1), see(3, 1), see(3, 2);  // 5 and 9 share point 1; 9 sees point 2 too
  see(4, 2);                        // and 4 shares point 2 with 9: {5, 9, 4}, the oldest is 4
  EXPECT_EQ(holdEachUnanchoredGroup(p), 1);
  const std::vector<bool> fixed{true, false, false, false, true};
  for (size_t i = 0; i < fixed.size(); ++i) EXPECT_EQ(p.keyframes[i].fixed, fixed[i]) << "keyframe " << i;
  EXPECT_EQ(holdEachUnanchoredGroup(p), 0) << "every group is anchored now";
}

namespace {

void expectBitIdenticalRuns(BaLinearSolver solver) {
  const Window w = makeWindow(spec(600, 2));
  LocalBaParams params;
  params.linear_solver = solver;
  const LocalBaResult a = localBundleAdjustment(w.cam, w.problem, params),
                      b = localBundleAdjustment(w.cam, w.problem, params);
  ASSERT_EQ(a.keyframes.size(), b.keyframes.size());
  for (size_t i = 0; i < a.keyframes.size(); ++i)
    EXPECT_TRUE(sameBits(a.keyframes[i].T_c_w, b.keyframes[i].T_c_w));
  for (size_t j = 0; j < a.points.size(); ++j)
    EXPECT_EQ(0, std::memcmp(a.points[j].p_w.data(), b.points[j].p_w.data(), 3 * sizeof(double)));
  EXPECT_EQ(a.outlier, b.outlier);
  EXPECT_EQ(0, std::memcmp(&a.summary.final_cost, &b.summary.final_cost, sizeof(double)));
  EXPECT_EQ(a.summary.iterations, b.summary.iterations);
}

}  // namespace

// Both linear solvers: the dense one of local BA and the sparse one (CHOLMOD) of global BA.
TEST(LocalBundleAdjustment, BitIdenticalAcrossRuns) {
  for (const BaLinearSolver solver : {BaLinearSolver::kDenseSchur, BaLinearSolver::kSparseSchur}) {
    SCOPED_TRACE(solver == BaLinearSolver::kDenseSchur ? "dense" : "sparse");
    expectBitIdenticalRuns(solver);
  }
}

TEST(LocalBundleAdjustment, SparseSchurAgreesWithDenseSchur) {
  const Window w = makeWindow(spec(600, 3));
  LocalBaParams sparse;
  sparse.linear_solver = BaLinearSolver::kSparseSchur;
  const LocalBaResult d = localBundleAdjustment(w.cam, w.problem),
                      s = localBundleAdjustment(w.cam, w.problem, sparse);
  ASSERT_EQ(d.keyframes.size(), s.keyframes.size());
  for (size_t i = 0; i < d.keyframes.size(); ++i) {
    EXPECT_LT(centreError(d.keyframes[i].T_c_w, s.keyframes[i].T_c_w), 1e-6);
    EXPECT_LT(rotationErrorDeg(d.keyframes[i].T_c_w, s.keyframes[i].T_c_w), 1e-6);
  }
  EXPECT_EQ(d.outlier, s.outlier);
  EXPECT_NEAR(d.summary.final_cost, s.summary.final_cost, 1e-6 * d.summary.final_cost);
}

TEST(LocalBundleAdjustment, AbortFlagStopsIt) {
  const Window w = makeWindow(spec(600, 4));
  std::atomic<bool> abort{true};
  const LocalBaResult r = localBundleAdjustment(w.cam, w.problem, {}, &abort);
  EXPECT_TRUE(r.aborted);
  EXPECT_EQ(r.summary.iterations, 0);
  ASSERT_EQ(r.keyframes.size(), 10u);
  for (const BaRefinedKeyframe& k : r.keyframes)
    EXPECT_TRUE(k.T_c_w.matrix() == w.problem.keyframes[k.index].T_c_w.matrix());
  for (size_t j = 0; j < r.points.size(); ++j) EXPECT_TRUE(r.points[j].p_w == w.problem.points[j].p_w);
  // Its outliers are judged at the starting values: the perturbation makes most of them outliers.
  EXPECT_GT(r.summary.num_outliers, 0);

  abort = false;
  const LocalBaResult full = localBundleAdjustment(w.cam, w.problem, {}, &abort);
  EXPECT_FALSE(full.aborted);
  EXPECT_GT(full.summary.iterations, 5);
}

TEST(LocalBundleAdjustment, PointBehindACameraIsAnOutlier) {
  Window w = makeWindow(spec(300, 5, 0.0));
  // A point 4 m behind keyframe 15 (so behind 16 too), "seen" by both at plausible pixels: both
  // observations are outliers, and the point, with nothing else to go by, comes back as given.
  const Eigen::Vector3d behind = w.problem.keyframes[15].T_c_w.inverse() * Eigen::Vector3d(0.5, 0.2, -4);
  const size_t j = w.problem.points.size();
  w.problem.points.push_back({99999, behind});
  w.problem.observations.push_back({15, j, Eigen::Vector2d(600, 180), -1, 1});
  w.problem.observations.push_back({16, j, Eigen::Vector2d(620, 190), 500, 1});
  const LocalBaResult r = localBundleAdjustment(w.cam, w.problem);
  EXPECT_TRUE(r.outlier[r.outlier.size() - 2]);
  EXPECT_TRUE(r.outlier[r.outlier.size() - 1]);
  EXPECT_TRUE(r.points[j].p_w == behind);
  EXPECT_LT(r.summary.num_outliers, 0.01 * r.outlier.size() + 2);
}

TEST(LocalBundleAdjustment, AllKeyframesFixedRefinesThePointsOnly) {
  Window w = makeWindow(spec(400, 6));
  for (size_t i = 0; i < w.problem.keyframes.size(); ++i) w.problem.keyframes[i] = w.truth.keyframes[i];
  for (BaKeyframe& kf : w.problem.keyframes) kf.fixed = true;
  const LocalBaResult r = localBundleAdjustment(w.cam, w.problem);
  EXPECT_TRUE(r.keyframes.empty());
  // Against the optimum: the same adjustment started at the true points.
  BaProblem from_truth = w.problem;
  from_truth.points = w.truth.points;
  Window optimum = w;
  optimum.truth.points = localBundleAdjustment(w.cam, from_truth).points;
  const Errors before = errors(optimum, {}, w.problem.points), after = errors(optimum, {}, r.points);
  EXPECT_LT(after.point_m, 0.02 * before.point_m);
}

TEST(LocalBundleAdjustment, InvalidInputThrows) {
  const Window w = makeWindow(spec(50, 7));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto edited = [&](auto edit) {
    BaProblem pb = w.problem;
    edit(pb);
    return pb;
  };
  const char* who = "localBundleAdjustment: ";
  EXPECT_THROW_WITH(
      localBundleAdjustment(w.cam, edited([](BaProblem& pb) { pb.observations[3].keyframe = 20; })),
      std::invalid_argument, "observation 3: keyframe index 20 out of range (20 keyframes)");
  EXPECT_THROW_WITH(
      localBundleAdjustment(w.cam, edited([](BaProblem& pb) { pb.observations[3].point = 50; })),
      std::invalid_argument, "point index 50 out of range");
  EXPECT_THROW_WITH(
      localBundleAdjustment(w.cam, edited([](BaProblem& pb) { pb.keyframes[4].id = pb.keyframes[5].id; })),
      std::invalid_argument, "duplicate keyframe id 1005");
  EXPECT_THROW_WITH(
      localBundleAdjustment(w.cam, edited([](BaProblem& pb) { pb.points[7].id = pb.points[2].id; })),
      std::invalid_argument, "duplicate point id");
  EXPECT_THROW_WITH(localBundleAdjustment(w.cam, edited([&](BaProblem& pb) { pb.points[7].p_w.z() = nan; })),
                    std::invalid_argument, std::string(who) + "point 7 (id 5007) is not finite");
  EXPECT_THROW_WITH(
      localBundleAdjustment(w.cam, edited([&](BaProblem& pb) { pb.observations[2].uv.x() = nan; })),
      std::invalid_argument, "observation 2: pixel uv is not finite");
  EXPECT_THROW_WITH(
      localBundleAdjustment(w.cam, edited([](BaProblem& pb) { pb.observations[2].inv_sigma2 = 0; })),
      std::invalid_argument, "inv_sigma2 must be positive");
  EXPECT_THROW_WITH(localBundleAdjustment(w.cam, edited([&](BaProblem& pb) {
                                            pb.keyframes[12].T_c_w.translation().x() = nan;
                                          })),
                    std::invalid_argument, "keyframe 12 (id 1012) T_c_w is not finite");
  StereoCamera cam = w.cam;
  cam.fx = 0;
  EXPECT_THROW_WITH(localBundleAdjustment(cam, w.problem), std::invalid_argument, "focal lengths");
  LocalBaParams p;
  p.robust_iterations = -1;
  EXPECT_THROW_WITH(localBundleAdjustment(w.cam, w.problem, p), std::invalid_argument, "robust_iterations");
  // An empty problem is not an error.
  const LocalBaResult empty = localBundleAdjustment(w.cam, BaProblem{});
  EXPECT_TRUE(empty.keyframes.empty() && empty.points.empty() && empty.outlier.empty());
}
