// The renderer's promises: exact pinhole geometry and stereo disparity, occlusion, loops that look alike,
// and bit-for-bit determinism.
#include "binloop/sim/stereo_renderer.h"

#include <algorithm>
#include <cmath>

#include <filesystem>
#include <fstream>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "binloop/io/trajectory_io.h"
#include "binloop/sim/view_renderer.h"
#include "support/test_support.h"

using namespace binloop;
using namespace binloop::sim;

namespace {

// A straight 100 m route along +z with nothing on it, and a camera with no blur (sharp edges to measure).
struct EmptyStreet {
  std::vector<Pose3> route;
  World world;
  StereoCamera cam = kitti00Camera();
  EmptyStreet() : route(makeRoute()), world(makeWorld(route)) {}
  static std::vector<Pose3> makeRoute() {
    std::vector<Pose3> r;
    for (int i = 0; i <= 100; ++i) {
      Pose3 T = Pose3::Identity();
      T.translation() = Eigen::Vector3d(0, 0, i);
      r.push_back(T);
    }
    return r;
  }
  static World makeWorld(const std::vector<Pose3>& route) {
    WorldParams p;
    p.populate = false;
    return World::build(route, TextureBank::build({}, 3), p, 3);
  }
  Quad facade(const Eigen::Vector3f& o, const Eigen::Vector3f& a, float lu, float lv) const {
    Quad q;
    q.o = o;
    q.a = a.normalized();
    q.b = Eigen::Vector3f(0, -1, 0);
    q.lu = lu;
    q.lv = lv;
    q.texture = world.bank().facades[0];
    q.texels_per_m = 60;
    return q;
  }
};

// First column (from the left) on row y whose depth is within tol of `z`, or -1.
int firstColumnAtDepth(const cv::Mat& depth, int y, float z, float tol) {
  for (int x = 0; x < depth.cols; ++x)
    if (std::abs(depth.at<float>(y, x) - z) < tol) return x;
  return -1;
}

// Sub-pixel horizontal shift that best maps `right` onto `left` in a window (SSD over shifts, parabola fit).
double measuredDisparity(const cv::Mat& left, const cv::Mat& right, const cv::Rect& win, int dmin, int dmax) {
  std::vector<double> ssd;
  for (int d = dmin; d <= dmax; ++d) {
    cv::Mat l, r;
    left(win).convertTo(l, CV_64F);
    right(win - cv::Point(d, 0)).convertTo(r, CV_64F);
    ssd.push_back(cv::norm(l, r, cv::NORM_L2SQR));
  }
  const int k = static_cast<int>(std::min_element(ssd.begin(), ssd.end()) - ssd.begin());
  if (k == 0 || k + 1 == static_cast<int>(ssd.size())) return dmin + k;
  const double a = ssd[k - 1], b = ssd[k], c = ssd[k + 1];
  return dmin + k + 0.5 * (a - c) / (a - 2 * b + c);
}

}  // namespace

TEST(StereoRenderer, FrontoParallelFacadeLandsWhereTheCameraModelSays) {
  EmptyStreet s;
  // A wall 20 m ahead, x from -3 to 5 m, from 1 m below the camera's ground up to 2 m above the camera.
  const float Z = 20;
  s.world.addQuads({s.facade({-3, 1.65f, Z}, {1, 0, 0}, 8, 3.65f)});
  RenderOptions opt;
  opt.blur_sigma = 0;
  StereoRenderer r(s.world, s.cam, opt, 1);
  cv::Mat left, right, depth;
  r.render(0, 0, Pose3::Identity(), &left, &right, &depth);

  // Left edge: the projected corner x = fx*(-3)/Z + cx; the first covered pixel centre lies within half a
  // pixel of the boundary.
  const double x_edge = s.cam.fx * -3.0 / Z + s.cam.cx;
  const int col = firstColumnAtDepth(depth, 150, Z, 1e-3f);
  ASSERT_GE(col, 0);
  EXPECT_LE(std::abs((col - 0.5) - x_edge), 0.5) << "edge at column " << col << ", predicted " << x_edge;
  // Top edge: y = fy*(-2)/Z + cy.
  const double y_edge = s.cam.fy * -2.0 / Z + s.cam.cy;
  int row = -1;
  for (int y = 0; y < depth.rows && row < 0; ++y)
    if (std::abs(depth.at<float>(y, 600) - Z) < 1e-3f) row = y;
  EXPECT_LE(std::abs((row - 0.5) - y_edge), 0.5) << "top edge at row " << row << ", predicted " << y_edge;

  // Stereo: the right image is the left shifted by fx*b/Z.
  const double d_pred = s.cam.bf() / Z;
  const double d_meas = measuredDisparity(left, right, cv::Rect(560, 130, 80, 40), 14, 25);
  EXPECT_NEAR(d_meas, d_pred, 0.5) << "predicted " << d_pred;
  // Exactly: in the right camera's own depth map, the wall's left edge moved by fx*b/Z.
  Pose3 T_w_r = Pose3::Identity();
  T_w_r.translation().x() = s.cam.baseline_m;
  cv::Mat gray_r, depth_r;
  ViewRenderer(180.0).render(s.world, s.cam, T_w_r, &gray_r, &depth_r);
  const int col_r = firstColumnAtDepth(depth_r, 150, Z, 1e-3f);
  EXPECT_LE(std::abs((col_r - 0.5) - (x_edge - d_pred)), 0.5) << "right edge at " << col_r;
}

TEST(StereoRenderer, ObliqueFacadeDepthMatchesRayPlaneIntersection) {
  EmptyStreet s;
  // A façade turned 35° about the vertical, 12–25 m ahead on the right.
  const Eigen::Vector3f o(2, 1.65f, 12), a(std::sin(0.6f), 0, std::cos(0.6f));
  s.world.addQuads({s.facade(o, a, 15, 10)});
  RenderOptions opt;
  opt.blur_sigma = 0;
  StereoRenderer r(s.world, s.cam, opt, 1);
  cv::Mat left, right, depth;
  r.render(0, 0, Pose3::Identity(), &left, &right, &depth);
  const Eigen::Vector3f n = a.cross(Eigen::Vector3f(0, -1, 0)).normalized();
  int checked = 0;
  for (int y = 60; y < 200; y += 20)
    for (int x = 700; x < 1200; x += 25) {
      const Eigen::Vector3f ray((x - s.cam.cx) / s.cam.fx, (y - s.cam.cy) / s.cam.fy, 1);
      const float t = n.dot(o) / n.dot(ray);  // z-depth of the plane along this pixel's ray
      const Eigen::Vector3f p = t * ray;
      const float u = (p - o).dot(a), v = -(p - o).y();
      if (u < 0.5f || u > 14.5f || v < 0.5f || v > 9.5f || t <= 0) continue;
      EXPECT_NEAR(depth.at<float>(y, x), t, 1e-3f * t) << "pixel " << x << "," << y;
      ++checked;
    }
  EXPECT_GT(checked, 30);
}

TEST(StereoRenderer, NearerSurfaceOccludesFartherOne) {
  EmptyStreet s;
  s.world.addQuads({s.facade({-5, 1.65f, 30}, {1, 0, 0}, 10, 6), s.facade({-1, 1.65f, 10}, {1, 0, 0}, 2, 3)});
  StereoRenderer r(s.world, s.cam, {}, 1);
  cv::Mat left, right, depth;
  r.render(0, 0, Pose3::Identity(), &left, &right, &depth);
  // Pixel straight ahead at the small near wall's height sees it, not the far wall behind; the same
  // holds in whichever order the quads were added (the far one was first).
  EXPECT_NEAR(depth.at<float>(static_cast<int>(s.cam.cy), static_cast<int>(s.cam.cx)), 10.0f, 1e-3f);
  EXPECT_NEAR(depth.at<float>(static_cast<int>(s.cam.cy), static_cast<int>(s.cam.cx + s.cam.fx * 4.0 / 30)),
              30.0f, 1e-3f);
}

TEST(StereoRenderer, SameSeedSameBytesOtherSeedOtherTextures) {
  EmptyStreet s;
  test::TempDir tmp;
  auto render_to = [&](uint64_t seed, const std::string& dir) {
    auto world = World::build(s.route, TextureBank::build(defaultTexturePhotos(), seed), {}, seed);
    RenderOptions opt;
    opt.noise_sigma = 2.0;  // noise is seeded too
    StereoRenderer r(world, s.cam, opt, seed);
    SequenceJob job{s.route, std::vector<double>(s.route.size(), 0.0), 10, 30, 10, dir};
    for (size_t i = 0; i < job.times.size(); ++i) job.times[i] = 0.1 * i;
    renderSequence(r, job);
  };
  render_to(7, tmp / "a");
  render_to(7, tmp / "b");
  render_to(8, tmp / "c");
  auto bytes = [](const std::string& p) {
    std::ifstream f(p, std::ios::binary);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
  };
  int same_ab = 0, same_ac = 0;
  for (const char* f :
       {"image_0/000000.png", "image_1/000001.png", "image_0/000002.png", "poses.txt", "times.txt"}) {
    const auto a = bytes(tmp / "a/" + f), b = bytes(tmp / "b/" + f), c = bytes(tmp / "c/" + f);
    ASSERT_FALSE(a.empty()) << f;
    same_ab += a == b;
    same_ac += a == c;
  }
  EXPECT_EQ(same_ab, 5);
  EXPECT_EQ(same_ac, 2);  // only poses.txt and times.txt agree
}

// Loops: frames that ground truth says are at the same place share many more ORB matches than frames of
// distinct places.
TEST(StereoRenderer, LoopPairsOfRoute06MatchFarBetterThanDistinctPlaces) {
  const std::string poses = test::sharedData("kitti/poses/06.txt"),
                    gt = test::sharedData("kitti/loop_gt/06.txt");
  BINLOOP_REQUIRE_DATA(poses);
  BINLOOP_REQUIRE_DATA(gt);
  const auto route = readKittiPoses(poses);
  const auto pairs = readIndexPairs(gt);
  const auto world = World::build(route, TextureBank::build(defaultTexturePhotos(), 1), {}, 1);
  StereoRenderer r(world, kitti00Camera(), {}, 1);
  auto orb = cv::ORB::create(2000);
  cv::BFMatcher matcher(cv::NORM_HAMMING);
  auto features = [&](int frame) {
    cv::Mat left, right, desc;
    std::vector<cv::KeyPoint> kps;
    r.render(frame, 0.1 * frame, route[frame], &left, &right);
    orb->detectAndCompute(left, cv::noArray(), kps, desc);
    return desc;
  };
  auto ratioMatches = [&](const cv::Mat& a, const cv::Mat& b) {
    std::vector<std::vector<cv::DMatch>> knn;
    matcher.knnMatch(a, b, knn, 2);
    int good = 0;
    for (const auto& m : knn)
      if (m.size() == 2 && m[0].distance < 0.75f * m[1].distance) ++good;
    return good;
  };
  // Loop pairs: for queries spread over the revisit (827..1100), the gt reference closest in time to q-827.
  std::vector<int> loop_counts, distinct_counts;
  for (int q : {840, 880, 920, 960, 1000, 1040, 1080}) {
    int ref = -1;
    for (const auto& [a, b] : pairs)
      if (a == q && (ref < 0 || std::abs(b - (q - 827)) < std::abs(ref - (q - 827)))) ref = b;
    ASSERT_GE(ref, 0) << "no ground-truth pair for query " << q;
    const cv::Mat dq = features(q);
    loop_counts.push_back(ratioMatches(dq, features(ref)));
    // A distinct place: the first of q-300, q-350, ... more than 100 m away (06 doubles back on itself).
    int far = q - 300;
    while (far > 0 && (route[q].translation() - route[far].translation()).norm() < 100.0) far -= 50;
    ASSERT_GT(far, 0);
    distinct_counts.push_back(ratioMatches(dq, features(far)));
  }
  std::sort(loop_counts.begin(), loop_counts.end());
  std::sort(distinct_counts.begin(), distinct_counts.end());
  std::ostringstream msg;
  msg << "ratio-test matches, loop pairs:";
  for (int c : loop_counts) msg << " " << c;
  msg << "; distinct places:";
  for (int c : distinct_counts) msg << " " << c;
  std::cout << msg.str() << "\n";
  EXPECT_GT(loop_counts.front(), 2 * distinct_counts.back()) << msg.str();
  EXPECT_GT(loop_counts[loop_counts.size() / 2], 4 * distinct_counts[distinct_counts.size() / 2])
      << msg.str();
}

// The road texture is 512 texels at 64 per metre: by default two views 8 m apart on a straight road see the
// same road, pixel for pixel, which is what let relocalisation lock on to the wrong place; the aperiodic
// ground does not repeat there.
TEST(StereoRenderer, TheAperiodicGroundDoesNotRepeatEveryEightMetres) {
  EmptyStreet s;
  auto roadDifference = [&](bool aperiodic) {
    WorldParams p;
    p.populate = false;
    p.aperiodic_ground = aperiodic;
    const World world = World::build(s.route, TextureBank::build({}, 3), p, 3);
    RenderOptions opt;
    opt.noise_sigma = 0;
    StereoRenderer r(world, s.cam, opt, 1);
    cv::Mat a, b, unused;
    r.render(20, 2.0, s.route[20], &a, &unused);
    r.render(28, 2.8, s.route[28], &b, &unused);
    const cv::Rect road(0, static_cast<int>(s.cam.cy) + 40, s.cam.width,
                        s.cam.height - static_cast<int>(s.cam.cy) - 40);
    return cv::norm(a(road), b(road), cv::NORM_L1) / road.area();
  };
  EXPECT_LT(roadDifference(false), 0.5);
  EXPECT_GT(roadDifference(true), 5.0);
}

// A U-turn of 12 m radius between two straights, climbing 5 m in 100 m (y down: y falls), the camera
// looking along the road: where the default ground turns with the camera and the rigid one does not.
std::vector<Pose3> climbingUTurn() {
  std::vector<Pose3> r;
  auto at = [&](const Eigen::Vector3d& p, double yaw) {
    Pose3 T = Pose3::Identity();
    T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()).toRotationMatrix();
    T.translation() = p;
    r.push_back(T);
  };
  const double kR = 12, kPi = std::acos(-1.0), grade = -0.05;
  double s = 0;  // path length so far
  for (int i = 0; i < 40; ++i, s += 1) at({0, grade * s, s}, 0);
  for (double a = 0; a < kPi; a += 1 / kR, s += 1)  // 1 m steps round the turn, to the right
    at({kR - kR * std::cos(a), grade * s, 40 + kR * std::sin(a)}, a);
  for (int i = 0; i < 40; ++i, s += 1) at({2 * kR, grade * s, 40.0 - i}, kPi);
  return r;
}

// Median over the ground pixels of camera A of |depth B renders there - depth of A's point in B| / depth,
// for points 4-30 m from A that B sees.
double groundMismatch(const World& world, const StereoCamera& cam, const Pose3& A, const Pose3& B) {
  ViewRenderer view;
  cv::Mat gray, depth_a, depth_b;
  view.render(world, cam, A, &gray, &depth_a);
  view.render(world, cam, B, &gray, &depth_b);
  std::vector<double> rel;
  for (int y = static_cast<int>(cam.cy) + 20; y < cam.height; y += 7) {
    for (int x = 0; x < cam.width; x += 7) {
      const double za = depth_a.at<float>(y, x);
      if (!(za > 4 && za < 30)) continue;
      const Eigen::Vector3d p_w =
          A * Eigen::Vector3d((x - cam.cx) / cam.fx * za, (y - cam.cy) / cam.fy * za, za);
      const Eigen::Vector3d p_b = B.inverse() * p_w;
      const double u = cam.fx * p_b.x() / p_b.z() + cam.cx, v = cam.fy * p_b.y() / p_b.z() + cam.cy;
      if (!(u >= 1 && v >= 1 && u < cam.width - 2 && v < cam.height - 2)) continue;
      cv::Mat patch;
      cv::getRectSubPix(depth_b, cv::Size(1, 1), cv::Point2f(static_cast<float>(u), static_cast<float>(v)),
                        patch);
      const double zb = patch.at<float>(0, 0);
      if (std::isfinite(zb)) rel.push_back(std::abs(zb - p_b.z()) / p_b.z());
    }
  }
  if (rel.size() < 100) return -1;
  std::nth_element(rel.begin(), rel.begin() + rel.size() / 2, rel.end());
  return rel[rel.size() / 2];
}

// Successive frames, and the two cameras of a pair, must see one road: a point of it lies where the other
// view's depth says. The default ground is a plane under each camera, tilted with the grade over +-20 m of
// route, so in a climbing U-turn it turns from frame to frame and differs between the cameras; the rigid
// ground (WorldParams::rigid_ground) is one surface.
TEST(StereoRenderer, TheRigidGroundIsOneSurfaceForEveryFrameAndBothCameras) {
  const std::vector<Pose3> route = climbingUTurn();
  const StereoCamera cam = kitti00Camera();
  Pose3 T_c_r = Pose3::Identity();
  T_c_r.translation() = Eigen::Vector3d(cam.baseline_m, 0, 0);
  const size_t apex = 40 + 19;
  for (bool rigid : {false, true}) {
    WorldParams p;
    p.populate = false;
    p.rigid_ground = rigid;
    const World world = World::build(route, TextureBank::build({}, 3), p, 3);
    std::ostringstream where;
    double worst_frames = 0, worst_stereo = 0;
    for (size_t i : {size_t{20}, apex - 10, apex, apex + 10}) {
      const double frames = groundMismatch(world, cam, route[i], route[i + 1]);
      const double stereo = groundMismatch(world, cam, route[i], route[i] * T_c_r);
      ASSERT_GE(frames, 0) << "frame " << i << ": too few ground points";
      ASSERT_GE(stereo, 0) << "frame " << i << ": too few ground points";
      where << " frame " << i << ": next frame " << frames << ", right camera " << stereo << ";";
      worst_frames = std::max(worst_frames, frames);
      worst_stereo = std::max(worst_stereo, stereo);
    }
    std::cout << (rigid ? "rigid" : "per-camera plane")
              << " ground, median relative depth mismatch:" << where.str() << "\n";
    if (rigid) {
      EXPECT_LT(worst_frames, 1e-3) << where.str();
      EXPECT_LT(worst_stereo, 1e-3) << where.str();
    } else {
      EXPECT_GT(worst_frames, 3e-3) << "the default ground was expected to move between frames"
                                    << where.str();
    }
  }
}

TEST(StereoRenderer, RenderFramesNumbersFromZeroAndRendersTheRouteFrames) {
  EmptyStreet s;
  StereoRenderer r(s.world, s.cam, {}, 1);
  const auto frames = renderFrames(r, s.route, 97, 10);
  ASSERT_EQ(frames.size(), 4u) << "route frames 97..100: the route ends at 100";
  for (size_t k = 0; k < frames.size(); ++k) {
    EXPECT_EQ(frames[k].index, static_cast<int>(k));
    EXPECT_DOUBLE_EQ(frames[k].stamp_s, 0.1 * static_cast<double>(k));
    // The same images as route frame 97+k rendered alone: the noise follows the route frame, not k.
    cv::Mat left, right;
    r.render(static_cast<int>(97 + k), 0.1 * static_cast<double>(97 + k), s.route[97 + k], &left, &right);
    EXPECT_EQ(cv::norm(left, frames[k].left, cv::NORM_INF), 0) << "frame " << k;
    EXPECT_EQ(cv::norm(right, frames[k].right, cv::NORM_INF), 0) << "frame " << k;
  }
  cv::Mat other, unused;
  r.render(0, 0, s.route[97], &other, &unused);
  EXPECT_GT(cv::norm(other, frames[0].left, cv::NORM_INF), 0) << "frame numbers seed the noise";
}
