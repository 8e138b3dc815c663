// Every stage message survives core -> ROS -> core field for field, and malformed ROS messages are refused
// with the field named.
#include "binloop_ros/stage_msg_conversion.h"

#include <random>

#include "support/test_support.h"

namespace core = binloop::msg;
using binloop_ros::ConversionError;
using binloop_ros::fromRos;
using binloop_ros::toRos;

namespace {

binloop::Pose3 somePose(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  binloop::Pose3 T = binloop::Pose3::Identity();
  T.linear() = Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng)).normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(u(rng), u(rng), u(rng)) * 100;
  return T;
}

void expectPose(const binloop::Pose3& a, const binloop::Pose3& b) {
  EXPECT_LT((a.matrix() - b.matrix()).cwiseAbs().maxCoeff(), 1e-12);
}

core::MapPoint somePoint(std::mt19937& rng, uint64_t id) {
  core::MapPoint p;
  p.id = id;
  p.p_w = Eigen::Vector3d(rng() % 1000, rng() % 1000, rng() % 1000) * 0.01;
  for (auto& w : p.descriptor.w) w = (uint64_t(rng()) << 32) | rng();
  p.normal = Eigen::Vector3f(0.6f, 0.f, 0.8f);
  p.min_distance = 1.5f;
  p.max_distance = 40.25f;
  p.reference = 7;
  p.observations = 4;
  return p;
}

core::KeyframeState someState(std::mt19937& rng, uint64_t id, size_t n) {
  core::KeyframeState s;
  s.id = id;
  s.T_w_c = somePose(rng);
  for (size_t i = 0; i < n; ++i) s.point_ids.push_back(i % 3 ? 100 + i : binloop::kNoId);
  s.covisible = {{id + 1, 120}, {id + 2, 16}};
  s.parent = id - 1;
  return s;
}

void expectPoint(const core::MapPoint& a, const core::MapPoint& b) {
  EXPECT_EQ(a.id, b.id);
  EXPECT_EQ(a.p_w, b.p_w);
  EXPECT_EQ(a.descriptor, b.descriptor);
  EXPECT_EQ(a.normal, b.normal);
  EXPECT_EQ(a.min_distance, b.min_distance);
  EXPECT_EQ(a.max_distance, b.max_distance);
  EXPECT_EQ(a.reference, b.reference);
  EXPECT_EQ(a.observations, b.observations);
}

void expectState(const core::KeyframeState& a, const core::KeyframeState& b) {
  EXPECT_EQ(a.id, b.id);
  expectPose(a.T_w_c, b.T_w_c);
  EXPECT_EQ(a.point_ids, b.point_ids);
  ASSERT_EQ(a.covisible.size(), b.covisible.size());
  for (size_t i = 0; i < a.covisible.size(); ++i) {
    EXPECT_EQ(a.covisible[i].id, b.covisible[i].id);
    EXPECT_EQ(a.covisible[i].weight, b.covisible[i].weight);
  }
  EXPECT_EQ(a.parent, b.parent);
}

core::KeyFrame someKeyframe(std::mt19937& rng) {
  core::KeyFrame kf;
  kf.id = (uint64_t{1} << 56) | 42;
  kf.revision = 2;
  kf.frame_index = 1234;
  kf.stamp_s = 123.456789;
  kf.camera = binloop::kitti00Camera();
  for (int i = 0; i < 50; ++i) {
    core::KeyPoint k{float(rng() % 1241) + 0.25f, float(rng() % 376) + 0.5f,
                     float(rng() % 360),          uint8_t(i % 8),
                     i % 4 ? 500.125f : -1.f,     i % 4 ? 12.5f : -1.f};
    kf.keypoints.push_back(k);
    binloop::Desc256 d;
    for (auto& w : d.w) w = (uint64_t(rng()) << 32) | rng();
    kf.descriptors.push_back(d);
  }
  kf.state = someState(rng, kf.id, kf.keypoints.size());
  kf.new_points = {somePoint(rng, 101), somePoint(rng, 102)};
  kf.corrections_seen = 3;
  return kf;
}

}  // namespace

TEST(StageMsgConversion, KeyFrameRoundTrip) {
  std::mt19937 rng(1);
  const core::KeyFrame a = someKeyframe(rng);
  const binloop::KeyFrame m = toRos(a, "map");
  EXPECT_EQ(m.header.frame_id, "map");
  EXPECT_EQ(m.descriptors.size(), 50u * 32u);
  const core::KeyFrame b = fromRos(m);
  EXPECT_EQ(a.id, b.id);
  EXPECT_EQ(a.revision, b.revision);
  EXPECT_EQ(a.frame_index, b.frame_index);
  EXPECT_NEAR(a.stamp_s, b.stamp_s, 1e-9);
  EXPECT_TRUE(a.camera == b.camera);
  EXPECT_EQ(a.scale_factor, b.scale_factor);
  EXPECT_EQ(a.levels, b.levels);
  ASSERT_EQ(a.keypoints.size(), b.keypoints.size());
  for (size_t i = 0; i < a.keypoints.size(); ++i) {
    EXPECT_EQ(a.keypoints[i].x, b.keypoints[i].x);
    EXPECT_EQ(a.keypoints[i].y, b.keypoints[i].y);
    EXPECT_EQ(a.keypoints[i].angle, b.keypoints[i].angle);
    EXPECT_EQ(a.keypoints[i].octave, b.keypoints[i].octave);
    EXPECT_EQ(a.keypoints[i].right_x, b.keypoints[i].right_x);
    EXPECT_EQ(a.keypoints[i].depth, b.keypoints[i].depth);
  }
  EXPECT_EQ(a.descriptors, b.descriptors);
  expectState(a.state, b.state);
  ASSERT_EQ(b.new_points.size(), 2u);
  for (size_t i = 0; i < 2; ++i) expectPoint(a.new_points[i], b.new_points[i]);
  EXPECT_EQ(a.corrections_seen, b.corrections_seen);
}

TEST(StageMsgConversion, LocalMapUpdateRoundTrip) {
  std::mt19937 rng(2);
  core::LocalMapUpdate a;
  a.sequence = 9;
  a.keyframe = 77;
  a.keyframes = {someState(rng, 77, 5), someState(rng, 78, 0)};
  a.points = {somePoint(rng, 5), somePoint(rng, 6), somePoint(rng, 7)};
  a.fused = {{11, 12}, {13, 14}};
  a.culled_points = {21, 22};
  a.culled_keyframes = {31};
  a.corrections_seen = 2;
  a.correction = true;
  a.total_ms = 12.5;
  a.ba_ms = 8.25;
  a.triangulation_ms = 1.5;
  a.ba_iterations = 7;
  a.ba_outliers = 3;
  a.points_triangulated = 40;
  a.points_fused_across_loop = 17;
  std_msgs::Header h;
  h.stamp = ros::Time(5.0);
  const core::LocalMapUpdate b = fromRos(toRos(a, h));
  EXPECT_EQ(a.sequence, b.sequence);
  EXPECT_EQ(a.keyframe, b.keyframe);
  ASSERT_EQ(b.keyframes.size(), 2u);
  for (size_t i = 0; i < 2; ++i) expectState(a.keyframes[i], b.keyframes[i]);
  ASSERT_EQ(b.points.size(), 3u);
  for (size_t i = 0; i < 3; ++i) expectPoint(a.points[i], b.points[i]);
  EXPECT_EQ(a.fused, b.fused);
  EXPECT_EQ(a.culled_points, b.culled_points);
  EXPECT_EQ(a.culled_keyframes, b.culled_keyframes);
  EXPECT_EQ(a.corrections_seen, b.corrections_seen);
  EXPECT_EQ(a.correction, b.correction);
  EXPECT_EQ(a.total_ms, b.total_ms);
  EXPECT_EQ(a.ba_ms, b.ba_ms);
  EXPECT_EQ(a.triangulation_ms, b.triangulation_ms);
  EXPECT_EQ(a.ba_iterations, b.ba_iterations);
  EXPECT_EQ(a.ba_outliers, b.ba_outliers);
  EXPECT_EQ(a.points_triangulated, b.points_triangulated);
  EXPECT_EQ(a.points_fused_across_loop, b.points_fused_across_loop);
}

TEST(StageMsgConversion, LoopCandidatesRoundTrip) {
  core::LoopCandidates a;
  a.query = 5;
  a.query_frame = 500;
  a.model = "vladpq";
  a.shadow = true;
  a.status = "found";
  a.detail = "2 above bar 0.31";
  a.candidates = {{3, 0.8, 0.9}, {4, 0.5, 0.6}};
  a.consistency = 2;
  a.accepted = 3;
  a.query_words = {7, 8, 9};
  a.accepted_words = {9, 10};
  a.timings = {{"signature", 1.25}, {"query", 0.5}};
  a.total_ms = 1.75;
  const core::LoopCandidates b = fromRos(toRos(a, std_msgs::Header()));
  EXPECT_EQ(a.query, b.query);
  EXPECT_EQ(a.query_frame, b.query_frame);
  EXPECT_EQ(a.model, b.model);
  EXPECT_EQ(a.shadow, b.shadow);
  EXPECT_EQ(a.status, b.status);
  EXPECT_EQ(a.detail, b.detail);
  ASSERT_EQ(b.candidates.size(), 2u);
  EXPECT_EQ(b.candidates[1].id, 4u);
  EXPECT_EQ(b.candidates[1].score, 0.5);
  EXPECT_EQ(b.candidates[1].confidence, 0.6);
  EXPECT_EQ(a.consistency, b.consistency);
  EXPECT_EQ(a.accepted, b.accepted);
  EXPECT_EQ(a.query_words, b.query_words);
  EXPECT_EQ(a.accepted_words, b.accepted_words);
  ASSERT_EQ(b.timings.size(), 2u);
  EXPECT_EQ(b.timings[0].step, "signature");
  EXPECT_EQ(b.timings[0].ms, 1.25);
  EXPECT_EQ(a.total_ms, b.total_ms);
}

TEST(StageMsgConversion, LoopClosureRoundTrip) {
  std::mt19937 rng(3);
  core::LoopClosure a;
  a.query = 50;
  a.match = 4;
  a.query_frame = 1500;
  a.match_frame = 40;
  a.model = "external";
  a.status = core::LoopStatus::kBeyondDriftBound;
  a.detail = "moves 7.2 m, bound 1.9 m";
  a.T_query_match = somePose(rng);
  a.matches = 120;
  a.inliers = 80;
  a.correction_m = 7.2;
  a.drift_bound_m = 1.9;
  a.residual_ratio = 0.1;
  a.keyframes_corrected = 0;
  a.verify_ms = 1.6;
  a.optimize_ms = 0;
  const core::LoopClosure b = fromRos(toRos(a, std_msgs::Header()));
  EXPECT_EQ(a.query, b.query);
  EXPECT_EQ(a.match, b.match);
  EXPECT_EQ(a.query_frame, b.query_frame);
  EXPECT_EQ(a.match_frame, b.match_frame);
  EXPECT_EQ(a.model, b.model);
  EXPECT_EQ(a.status, b.status);
  EXPECT_EQ(a.detail, b.detail);
  expectPose(a.T_query_match, b.T_query_match);
  EXPECT_EQ(a.matches, b.matches);
  EXPECT_EQ(a.inliers, b.inliers);
  EXPECT_EQ(a.correction_m, b.correction_m);
  EXPECT_EQ(a.drift_bound_m, b.drift_bound_m);
  EXPECT_EQ(a.residual_ratio, b.residual_ratio);
  EXPECT_EQ(a.keyframes_corrected, b.keyframes_corrected);
  EXPECT_EQ(a.verify_ms, b.verify_ms);
  EXPECT_EQ(a.optimize_ms, b.optimize_ms);
  EXPECT_EQ(binloop::LoopClosure::BEYOND_DRIFT_BOUND, toRos(a, std_msgs::Header()).status);
}

// The core's statuses are the message's constants, one for one; any other text is refused.
TEST(StageMsgConversion, LoopClosureStatusesAreTheMessageConstants) {
  const std::vector<std::pair<core::LoopStatus, std::string>> all = {
      {core::LoopStatus::kAccepted, binloop::LoopClosure::ACCEPTED},
      {core::LoopStatus::kHeld, binloop::LoopClosure::HELD},
      {core::LoopStatus::kAgreed, binloop::LoopClosure::AGREED},
      {core::LoopStatus::kTooFewMatches, binloop::LoopClosure::TOO_FEW_MATCHES},
      {core::LoopStatus::kNoConsensus, binloop::LoopClosure::NO_CONSENSUS},
      {core::LoopStatus::kTooFewInliers, binloop::LoopClosure::TOO_FEW_INLIERS},
      {core::LoopStatus::kBeyondDriftBound, binloop::LoopClosure::BEYOND_DRIFT_BOUND},
      {core::LoopStatus::kLargeResidual, binloop::LoopClosure::LARGE_RESIDUAL},
      {core::LoopStatus::kUnknownKeyframe, binloop::LoopClosure::UNKNOWN_KEYFRAME}};
  for (const auto& [status, text] : all) {
    core::LoopClosure a;
    a.status = status;
    const binloop::LoopClosure m = toRos(a, std_msgs::Header());
    EXPECT_EQ(m.status, text);
    EXPECT_EQ(fromRos(m).status, status) << text;
  }
  binloop::LoopClosure m = toRos(core::LoopClosure{}, std_msgs::Header());
  m.status = "found";
  EXPECT_THROW(fromRos(m), binloop_ros::ConversionError);
}

TEST(StageMsgConversion, CorrectionRoundTrip) {
  std::mt19937 rng(4);
  core::Correction a;
  a.sequence = 2;
  a.query = 60;
  a.match = 3;
  for (uint64_t id = 1; id <= 4; ++id) a.keyframes.push_back({id, somePose(rng), somePose(rng)});
  a.fused = {{600, 30}};
  a.fuse_by_projection = false;
  const core::Correction b = fromRos(toRos(a, std_msgs::Header()));
  EXPECT_EQ(a.sequence, b.sequence);
  EXPECT_EQ(a.query, b.query);
  EXPECT_EQ(a.match, b.match);
  ASSERT_EQ(b.keyframes.size(), 4u);
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(a.keyframes[i].id, b.keyframes[i].id);
    expectPose(a.keyframes[i].T_w_c_before, b.keyframes[i].T_w_c_before);
    expectPose(a.keyframes[i].T_w_c_after, b.keyframes[i].T_w_c_after);
  }
  EXPECT_EQ(a.fused, b.fused);
  EXPECT_EQ(a.fuse_by_projection, b.fuse_by_projection);
}

TEST(StageMsgConversion, TrackedFrameRoundTrip) {
  std::mt19937 rng(6);
  core::TrackedFrame a;
  a.frame_index = 17;
  a.stamp_s = 2.5;
  a.state = core::TrackingState::kRelocalized;
  a.T_w_c = somePose(rng);
  a.reference = 9;
  a.T_ref_c = somePose(rng);
  a.new_keyframe = 10;
  a.features = 2000;
  a.stereo_matches = 900;
  a.tracked_points = 400;
  a.reference_points = 310;
  a.mapping_queue = 2;
  a.problem = "none";
  a.extract_ms = 20.5;
  a.stereo_ms = 4.25;
  a.track_ms = 12.125;
  const core::TrackedFrame b = fromRos(toRos(a, "map"));
  EXPECT_EQ(a.frame_index, b.frame_index);
  EXPECT_NEAR(a.stamp_s, b.stamp_s, 1e-9);
  EXPECT_EQ(a.state, b.state);
  expectPose(a.T_w_c, b.T_w_c);
  EXPECT_EQ(a.reference, b.reference);
  expectPose(a.T_ref_c, b.T_ref_c);
  EXPECT_EQ(a.new_keyframe, b.new_keyframe);
  EXPECT_EQ(a.features, b.features);
  EXPECT_EQ(a.stereo_matches, b.stereo_matches);
  EXPECT_EQ(a.tracked_points, b.tracked_points);
  EXPECT_EQ(a.reference_points, b.reference_points);
  EXPECT_EQ(a.mapping_queue, b.mapping_queue);
  EXPECT_EQ(a.problem, b.problem);
  EXPECT_EQ(a.extract_ms, b.extract_ms);
  EXPECT_EQ(a.stereo_ms, b.stereo_ms);
  EXPECT_EQ(a.track_ms, b.track_ms);
  binloop::TrackedFrame m = toRos(a, "map");
  m.state = 7;
  EXPECT_THROW(fromRos(m), ConversionError);
}

TEST(StageMsgConversion, MalformedMessagesAreRefusedNamingTheField) {
  std::mt19937 rng(5);
  const binloop::KeyFrame good = toRos(someKeyframe(rng), "map");
  auto refusedWith = [](const binloop::KeyFrame& m, const std::string& field) {
    try {
      fromRos(m);
    } catch (const ConversionError& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
      return true;
    }
    return false;
  };
  binloop::KeyFrame m = good;
  m.descriptors.resize(m.descriptors.size() - 1);  // truncated
  EXPECT_TRUE(refusedWith(m, "descriptors"));
  m = good;
  m.state.point_ids.pop_back();
  EXPECT_TRUE(refusedWith(m, "point_ids"));
  m = good;
  m.id = 0;
  EXPECT_TRUE(refusedWith(m, "KeyFrame.id"));
  m = good;
  m.state.pose.orientation = geometry_msgs::Quaternion();  // all zero
  EXPECT_TRUE(refusedWith(m, "quaternion"));
  m = good;
  m.keypoints[3].octave = 8;
  EXPECT_TRUE(refusedWith(m, "octave"));
  m = good;
  m.camera.baseline_m = 0;
  EXPECT_TRUE(refusedWith(m, "baseline"));
  // Numbers that are not numbers, and a camera no keyframe grid should be sized by.
  m = good;
  m.state.pose.position.y = std::nan("");
  EXPECT_TRUE(refusedWith(m, "NaN or infinite"));
  m = good;
  m.keypoints[2].depth = std::numeric_limits<float>::infinity();
  EXPECT_TRUE(refusedWith(m, "KeyFrame.keypoints[2]"));
  m = good;
  m.camera.width = m.camera.height = 1000000;
  EXPECT_TRUE(refusedWith(m, "1000000x1000000 px"));
  m = good;
  ASSERT_FALSE(m.new_points.empty());
  m.new_points[0].position.z = std::nan("");
  EXPECT_TRUE(refusedWith(m, "MapPoint"));

  binloop::Correction c;
  c.sequence = 0;
  EXPECT_THROW(fromRos(c), ConversionError);
  binloop::LoopCandidates lc;
  EXPECT_THROW(fromRos(lc), ConversionError);  // query 0
}
