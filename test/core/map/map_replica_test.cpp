// MapReplica: a stage's own copy of the map, kept up to date from messages
// (include/binloop/map/map_replica.h).
#include "binloop/map/map_replica.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace binloop {
namespace {

using msg::KeyframeState;
using msg::MapPoint;

// Ids as the stages issue them: keyframes and points from tracking, a few from the other stages.
uint64_t trackingId(uint64_t n) { return (uint64_t{1} << 56) | n; }
uint64_t mappingId(uint64_t n) { return (uint64_t{2} << 56) | n; }

const MapPointId P1 = trackingId(101), P2 = trackingId(102), P3 = trackingId(103), P4 = trackingId(104),
                 P5 = trackingId(105);
const SlamKeyframeId K1 = trackingId(1), K2 = trackingId(2), K3 = trackingId(3);

MapPoint point(MapPointId id, double x = 0) {
  MapPoint p;
  p.id = id;
  p.p_w = Eigen::Vector3d(x, 1, 10);
  return p;
}

KeyframeState keyframe(SlamKeyframeId id, std::vector<MapPointId> point_ids, double x = 0) {
  KeyframeState k;
  k.id = id;
  k.T_w_c.translation() = Eigen::Vector3d(x, 0, 0);
  k.point_ids = std::move(point_ids);
  return k;
}

msg::KeyFrame keyframeMessage(SlamKeyframeId id, std::vector<MapPointId> point_ids,
                              std::vector<MapPointId> new_ids) {
  msg::KeyFrame kf;
  kf.id = id;
  kf.state = keyframe(id, std::move(point_ids));
  for (MapPointId p : new_ids) kf.new_points.push_back(point(p));
  return kf;
}

std::vector<SlamKeyframeId> sorted(std::vector<SlamKeyframeId> v) {
  std::sort(v.begin(), v.end());
  return v;
}

using Ids = std::vector<uint64_t>;

// K1 sees P1 P2 P3, K2 sees P2 P3 P4 (keypoint order as given; kNoId where a keypoint has no point).
MapReplica twoKeyframes() {
  MapReplica m;
  m.add(keyframeMessage(K1, {P1, kNoId, P2, P3}, {P1, P2, P3}));
  m.add(keyframeMessage(K2, {P2, P3, kNoId, P4}, {P4}));
  return m;
}

TEST(MapReplica, EmptyKnowsNothing) {
  MapReplica m;
  EXPECT_EQ(m.pointCount(), 0u);
  EXPECT_EQ(m.keyframeCount(), 0u);
  EXPECT_EQ(m.lastKeyframe(), kNoId);
  EXPECT_EQ(m.resolve(P1), kNoId);
  EXPECT_EQ(m.resolve(kNoId), kNoId);
  EXPECT_EQ(m.point(P1), nullptr);
  EXPECT_EQ(m.keyframe(K1), nullptr);
  EXPECT_TRUE(m.observers(P1).empty());
}

TEST(MapReplica, AddStoresKeyframeAndItsNewPoints) {
  MapReplica m;
  m.add(keyframeMessage(K1, {P1, kNoId, P2}, {P1, P2}));
  EXPECT_EQ(m.pointCount(), 2u);
  EXPECT_EQ(m.keyframeCount(), 1u);
  EXPECT_EQ(m.lastKeyframe(), K1);
  ASSERT_NE(m.keyframe(K1), nullptr);
  EXPECT_EQ(m.keyframe(K1)->point_ids, (Ids{P1, kNoId, P2}));
  ASSERT_NE(m.point(P1), nullptr);
  EXPECT_EQ(m.point(P1)->id, P1);
  EXPECT_EQ(m.resolve(P2), P2);
  EXPECT_EQ(m.observers(P1), (Ids{K1}));
  EXPECT_EQ(m.observers(P2), (Ids{K1}));
  EXPECT_TRUE(m.observers(kNoId).empty()) << "kNoId keypoints are not an observed point";
}

TEST(MapReplica, UpsertPointOverwrites) {
  MapReplica m;
  m.upsertPoint(point(P1, 1));
  m.upsertPoint(point(P1, 5));
  EXPECT_EQ(m.pointCount(), 1u);
  EXPECT_EQ(m.point(P1)->p_w.x(), 5);
}

TEST(MapReplica, KeyframeNamingUnknownPointDropsIt) {
  // resolve() is kNoId for a point never known, so the keyframe does not name it (points come first).
  MapReplica m;
  m.upsertPoint(point(P1));
  m.upsertKeyframe(keyframe(K1, {P1, P2}));
  EXPECT_EQ(m.keyframe(K1)->point_ids, (Ids{P1, kNoId}));
  EXPECT_TRUE(m.observers(P2).empty());
}

TEST(MapReplica, ObserversIndex) {
  MapReplica m = twoKeyframes();
  EXPECT_EQ(m.pointCount(), 4u);
  EXPECT_EQ(m.keyframeCount(), 2u);
  EXPECT_EQ(m.observers(P1), (Ids{K1}));
  EXPECT_EQ(sorted(m.observers(P2)), (Ids{K1, K2}));
  EXPECT_EQ(sorted(m.observers(P3)), (Ids{K1, K2}));
  EXPECT_EQ(m.observers(P4), (Ids{K2}));
}

TEST(MapReplica, ReupsertedKeyframeRelinksObservers) {
  MapReplica m = twoKeyframes();
  // K1 refined by local mapping: it lost P1 and P3 and now sees P4.
  m.upsertKeyframe(keyframe(K1, {kNoId, P4, P2, kNoId}, 2.0));
  EXPECT_TRUE(m.observers(P1).empty());
  EXPECT_EQ(m.observers(P3), (Ids{K2}));
  EXPECT_EQ(sorted(m.observers(P4)), (Ids{K1, K2}));
  EXPECT_EQ(sorted(m.observers(P2)), (Ids{K1, K2}));
  EXPECT_EQ(m.keyframe(K1)->T_w_c.translation().x(), 2.0);
  EXPECT_EQ(m.keyframeCount(), 2u);
  // The same state again changes nothing and lists no keyframe twice.
  m.upsertKeyframe(keyframe(K1, {kNoId, P4, P2, kNoId}, 2.0));
  EXPECT_EQ(sorted(m.observers(P4)), (Ids{K1, K2}));
}

// The lists stay in the order the keyframes were made, whatever order updates send them again in, whether or
// not a point kept its slot: a keyframe re-sent with its points is then only copied.
TEST(MapReplica, ObserverListsStayInTheOrderKeyframesWereMade) {
  MapReplica m = twoKeyframes();
  m.upsertKeyframe(keyframe(K3, {P2, P3}));
  EXPECT_EQ(m.observers(P2), (Ids{K1, K2, K3}));
  m.upsertKeyframe(keyframe(K1, {P1, kNoId, P2, P3}, 1.0));  // the same points: only the pose moved
  EXPECT_EQ(m.keyframe(K1)->T_w_c.translation().x(), 1.0);
  EXPECT_EQ(m.observers(P2), (Ids{K1, K2, K3}));
  EXPECT_EQ(m.observers(P3), (Ids{K1, K2, K3}));
  EXPECT_EQ(m.observers(P1), (Ids{K1}));
  m.upsertKeyframe(keyframe(K2, {P3, P2, kNoId, kNoId}));  // P2 and P3 swapped slots, P4 dropped
  EXPECT_EQ(m.observers(P2), (Ids{K1, K2, K3}));
  EXPECT_EQ(m.observers(P3), (Ids{K1, K2, K3}));
  EXPECT_TRUE(m.observers(P4).empty());
  m.upsertKeyframe(keyframe(K1, {P1, kNoId, kNoId, P3}));  // K1 drops P2, which the others still see
  EXPECT_EQ(m.observers(P2), (Ids{K2, K3}));
  EXPECT_EQ(m.observers(P3), (Ids{K1, K2, K3}));
  m.upsertKeyframe(keyframe(K1, {P1, P2, kNoId, P3}));  // and sees it again: back in its place, not last
  EXPECT_EQ(m.observers(P2), (Ids{K1, K2, K3}));
}

TEST(MapReplica, KeyframeNamingAPointTwiceIsOneObserver) {
  MapReplica m;
  m.upsertPoint(point(P1));
  m.upsertKeyframe(keyframe(K1, {P1, P1}));
  EXPECT_EQ(m.observers(P1), (Ids{K1}));
  m.removeKeyframe(K1);
  EXPECT_TRUE(m.observers(P1).empty());
}

TEST(MapReplica, RemoveKeyframeUnlinksIt) {
  MapReplica m = twoKeyframes();
  m.removeKeyframe(K1);
  EXPECT_EQ(m.keyframe(K1), nullptr);
  EXPECT_EQ(m.keyframeCount(), 1u);
  EXPECT_TRUE(m.observers(P1).empty());
  EXPECT_EQ(m.observers(P2), (Ids{K2}));
  // Its points stay: culling points is local mapping's decision.
  EXPECT_EQ(m.pointCount(), 4u);
  m.removeKeyframe(K3);  // unknown: nothing happens
  EXPECT_EQ(m.keyframeCount(), 1u);
}

TEST(MapReplica, LastKeyframeIsTheHighestCounter) {
  MapReplica m;
  m.upsertKeyframe(keyframe(K2, {}));
  EXPECT_EQ(m.lastKeyframe(), K2);
  m.upsertKeyframe(keyframe(K1, {}));  // an older one refined later
  EXPECT_EQ(m.lastKeyframe(), K2);
  m.upsertKeyframe(keyframe(K3, {}));
  EXPECT_EQ(m.lastKeyframe(), K3);
}

TEST(MapReplica, FuseReplacesRemovedWithKept) {
  MapReplica m = twoKeyframes();
  m.fuse(P1, P4);  // P1 (seen by K1) is P4 (seen by K2)
  EXPECT_EQ(m.pointCount(), 3u);
  EXPECT_EQ(m.resolve(P1), P4);
  ASSERT_NE(m.point(P1), nullptr);
  EXPECT_EQ(m.point(P1)->id, P4);
  EXPECT_EQ(m.resolve(P4), P4);
  // K1's keypoint that named P1 now names P4; the other keypoints are untouched.
  EXPECT_EQ(m.keyframe(K1)->point_ids, (Ids{P4, kNoId, P2, P3}));
  EXPECT_EQ(m.keyframe(K2)->point_ids, (Ids{P2, P3, kNoId, P4}));
  EXPECT_TRUE(m.observers(P1).empty());
  EXPECT_EQ(sorted(m.observers(P4)), (Ids{K1, K2}));
}

TEST(MapReplica, FusedPointIsNotResurrectedByAStaleUpsert) {
  MapReplica m = twoKeyframes();
  m.fuse(P1, P4);
  m.upsertPoint(point(P1, 9));  // sent before the sender knew of the fusion
  EXPECT_EQ(m.pointCount(), 3u);
  EXPECT_EQ(m.resolve(P1), P4);
  EXPECT_EQ(m.point(P1)->id, P4);
}

TEST(MapReplica, FuseOfTwoPointsSeenBySameKeyframesKeepsOneObserverEach) {
  MapReplica m = twoKeyframes();
  m.fuse(P2, P3);  // both seen by K1 and K2
  EXPECT_EQ(sorted(m.observers(P3)), (Ids{K1, K2}));
  EXPECT_TRUE(m.observers(P2).empty());
  for (SlamKeyframeId k : {K1, K2})
    for (MapPointId q : m.keyframe(k)->point_ids) EXPECT_NE(q, P2);
}

TEST(MapReplica, ResolveFollowsFusionChains) {
  MapReplica m = twoKeyframes();
  m.add(keyframeMessage(K3, {P5}, {P5}));
  m.fuse(P1, P2);
  m.fuse(P2, P3);
  m.fuse(P3, P5);
  EXPECT_EQ(m.resolve(P1), P5);
  EXPECT_EQ(m.resolve(P2), P5);
  EXPECT_EQ(m.resolve(P3), P5);
  EXPECT_EQ(m.point(P1)->id, P5);
  EXPECT_EQ(m.pointCount(), 2u);  // P4 and P5
  // A keyframe that saw both points of a fusion keeps one slot for the kept point (as local mapping does).
  EXPECT_EQ(m.keyframe(K1)->point_ids, (Ids{kNoId, kNoId, kNoId, P5}));
  EXPECT_EQ(m.keyframe(K2)->point_ids, (Ids{kNoId, P5, kNoId, P4}));
  EXPECT_EQ(sorted(m.observers(P5)), (Ids{K1, K2, K3}));
}

TEST(MapReplica, FuseIntoAnAlreadyFusedPointGoesToItsReplacement) {
  MapReplica m = twoKeyframes();
  m.fuse(P4, P3);
  m.fuse(P1, P4);  // P4 is P3 now
  EXPECT_EQ(m.resolve(P1), P3);
  EXPECT_EQ(m.keyframe(K1)->point_ids, (Ids{kNoId, kNoId, P2, P3}));
  EXPECT_EQ(sorted(m.observers(P3)), (Ids{K1, K2}));
  EXPECT_EQ(m.pointCount(), 2u);
}

TEST(MapReplica, FuseIntoItselfOrIntoUnknownDoesNothing) {
  MapReplica m = twoKeyframes();
  m.fuse(P1, P1);
  EXPECT_EQ(m.resolve(P1), P1);
  m.fuse(P1, P5);  // P5 was never known (or was culled): P1 must not disappear
  EXPECT_EQ(m.resolve(P1), P1);
  EXPECT_EQ(m.pointCount(), 4u);
  EXPECT_EQ(m.keyframe(K1)->point_ids, (Ids{P1, kNoId, P2, P3}));
  // The reverse of an existing fusion is no cycle.
  m.fuse(P1, P2);
  m.fuse(P2, P1);
  EXPECT_EQ(m.resolve(P1), P2);
  EXPECT_EQ(m.resolve(P2), P2);
}

// A Correction made from an older copy of the map may fuse a point that local mapping already fused into
// another: the replica must merge what that point became, or it keeps a stale duplicate forever.
TEST(MapReplica, FuseOfAnIdFusedMeanwhileMergesWhatItBecame) {
  MapReplica m = twoKeyframes();
  m.add(keyframeMessage(K3, {P5}, {P5}));
  m.fuse(P1, P4);  // local mapping: P1 is P4
  m.fuse(P1, P5);  // loop closing, not knowing that yet: P1 is P5, so P4 is P5 too
  EXPECT_EQ(m.resolve(P1), P5);
  EXPECT_EQ(m.resolve(P4), P5);
  EXPECT_EQ(m.keyframe(K1)->point_ids, (Ids{P5, kNoId, P2, P3}));
  EXPECT_EQ(m.keyframe(K2)->point_ids, (Ids{P2, P3, kNoId, P5}));
  EXPECT_EQ(m.pointCount(), 3u);  // P2, P3, P5
}

TEST(MapReplica, RemovePointClearsKeyframeReferences) {
  MapReplica m = twoKeyframes();
  m.removePoint(P2);
  EXPECT_EQ(m.point(P2), nullptr);
  EXPECT_EQ(m.resolve(P2), kNoId);
  EXPECT_EQ(m.pointCount(), 3u);
  EXPECT_EQ(m.keyframe(K1)->point_ids, (Ids{P1, kNoId, kNoId, P3}));
  EXPECT_EQ(m.keyframe(K2)->point_ids, (Ids{kNoId, P3, kNoId, P4}));
  EXPECT_TRUE(m.observers(P2).empty());
  // Re-upserting a keyframe that still names it (sent before the culling) drops it again.
  m.upsertKeyframe(keyframe(K1, {P1, kNoId, P2, P3}));
  EXPECT_EQ(m.keyframe(K1)->point_ids, (Ids{P1, kNoId, kNoId, P3}));
  EXPECT_TRUE(m.observers(P2).empty());
}

TEST(MapReplica, RemovingTheKeptPointLosesTheFusedIdsToo) {
  MapReplica m = twoKeyframes();
  m.fuse(P1, P4);
  m.removePoint(P4);
  EXPECT_EQ(m.resolve(P1), kNoId);
  EXPECT_EQ(m.point(P1), nullptr);
  EXPECT_EQ(m.keyframe(K1)->point_ids, (Ids{kNoId, kNoId, P2, P3}));
  EXPECT_EQ(m.keyframe(K2)->point_ids, (Ids{P2, P3, kNoId, kNoId}));
}

TEST(MapReplica, ApplyUpdateFusesBeforeCulling) {
  // The mapper fused P1 into P4, then culled P4: both are gone. (Culling first would leave P1 behind,
  // because a fusion into a point no longer there is ignored.)
  MapReplica m = twoKeyframes();
  msg::LocalMapUpdate u;
  u.fused = {{P1, P4}};
  u.culled_points = {P4};
  m.apply(u);
  EXPECT_EQ(m.resolve(P1), kNoId);
  EXPECT_EQ(m.resolve(P4), kNoId);
  EXPECT_EQ(m.pointCount(), 2u);
  EXPECT_EQ(m.keyframe(K1)->point_ids, (Ids{kNoId, kNoId, P2, P3}));
}

TEST(MapReplica, ApplyUpdateCullsBeforeUpsertingPoints) {
  MapReplica m = twoKeyframes();
  msg::LocalMapUpdate u;
  u.culled_points = {P1};
  u.points = {point(P1, 7)};
  m.apply(u);
  ASSERT_NE(m.point(P1), nullptr);
  EXPECT_EQ(m.point(P1)->p_w.x(), 7);
}

TEST(MapReplica, ApplyUpdateUpsertsPointsBeforeKeyframes) {
  // A point the mapper made and a keyframe naming it arrive in one update: the keyframe keeps it.
  MapReplica m = twoKeyframes();
  const MapPointId made = mappingId(1);
  msg::LocalMapUpdate u;
  u.points = {point(made, 3), point(P2, 4)};
  u.keyframes = {keyframe(K2, {P2, P3, made, P4}, 1.5)};
  m.apply(u);
  EXPECT_EQ(m.keyframe(K2)->point_ids, (Ids{P2, P3, made, P4}));
  EXPECT_EQ(m.observers(made), (Ids{K2}));
  EXPECT_EQ(m.point(P2)->p_w.x(), 4);
  EXPECT_EQ(m.keyframe(K2)->T_w_c.translation().x(), 1.5);
  EXPECT_EQ(m.pointCount(), 5u);
}

TEST(MapReplica, ApplyUpdateCullsKeyframes) {
  MapReplica m = twoKeyframes();
  msg::LocalMapUpdate u;
  u.culled_keyframes = {K1};
  u.keyframes = {keyframe(K2, {P2, P3, kNoId, P4}, 1)};
  m.apply(u);
  EXPECT_EQ(m.keyframe(K1), nullptr);
  EXPECT_EQ(m.keyframeCount(), 1u);
  EXPECT_TRUE(m.observers(P1).empty());
  EXPECT_EQ(m.observers(P2), (Ids{K2}));
}

TEST(MapReplica, KeyframeUpsertedWithAFusedIdGetsTheKeptId) {
  // The update's keyframe was serialised with an id that its own `fused` list removes.
  MapReplica m = twoKeyframes();
  msg::LocalMapUpdate u;
  u.fused = {{P1, P4}};
  u.keyframes = {keyframe(K1, {P1, kNoId, P2, P3})};
  m.apply(u);
  EXPECT_EQ(m.keyframe(K1)->point_ids, (Ids{P4, kNoId, P2, P3}));
  EXPECT_EQ(sorted(m.observers(P4)), (Ids{K1, K2}));
  EXPECT_TRUE(m.observers(P1).empty());

  // Later, tracking's own keyframe still names P1 (it matched P1 before the update arrived).
  m.add(keyframeMessage(K3, {P1, P2}, {}));
  EXPECT_EQ(m.keyframe(K3)->point_ids, (Ids{P4, P2}));
  EXPECT_EQ(sorted(m.observers(P4)), (Ids{K1, K2, K3}));
  EXPECT_TRUE(m.observers(P1).empty());
}

// A loop correction reaches tracking while K2 and K3 (K3 made on K2) are still on their way to mapping:
// the corrected map names K1 only. Carried, K2, K3 and the points they made move as K1 moved, and a point
// the update sends stays as sent; not carried, they stay.
TEST(MapReplica, KeyframesNotYetSentMoveWithTheirAncestorAfterACorrection) {
  auto build = [] {
    MapReplica m;
    m.add(keyframeMessage(K1, {P1}, {P1}));
    msg::KeyFrame k2 = keyframeMessage(K2, {P1, P2}, {P2});
    k2.state.parent = K1;
    k2.new_points[0].reference = K2;
    m.add(k2);
    msg::KeyFrame k3 = keyframeMessage(K3, {P2, P3}, {P3});
    k3.state.parent = K2;
    k3.state.T_w_c.translation() = Eigen::Vector3d(1, 0, 0);
    k3.new_points[0].reference = K3;
    m.add(k3);
    return m;
  };
  msg::LocalMapUpdate u;
  u.correction = true;
  u.corrections_seen = 1;
  KeyframeState k1 = keyframe(K1, {P1});
  k1.T_w_c.linear() = Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY()).toRotationMatrix();
  k1.T_w_c.translation() = Eigen::Vector3d(0, 0, 5);
  u.keyframes.push_back(k1);
  MapPoint p1 = point(P1, 3);
  p1.reference = K1;
  u.points.push_back(p1);
  MapPoint p2 =
      point(P2, -4);  // made by unsent K2, yet in the update (mapping had it from elsewhere): as sent
  p2.reference = K2;
  u.points.push_back(p2);

  MapReplica carried = build();
  carried.apply(u, true);
  const Pose3 d = k1.T_w_c;  // K1 was at the identity
  EXPECT_TRUE(carried.keyframe(K1)->T_w_c.isApprox(d));
  EXPECT_TRUE(carried.keyframe(K2)->T_w_c.isApprox(d));
  Pose3 k3_before = Pose3::Identity();
  k3_before.translation() = Eigen::Vector3d(1, 0, 0);
  EXPECT_TRUE(carried.keyframe(K3)->T_w_c.isApprox(d * k3_before));
  EXPECT_TRUE(carried.point(P2)->p_w.isApprox(p2.p_w));
  EXPECT_TRUE(carried.point(P3)->p_w.isApprox(d * point(P3).p_w));
  EXPECT_TRUE(carried.point(P1)->p_w.isApprox(p1.p_w));  // as sent
  EXPECT_EQ(carried.observers(P1), (Ids{K1, K2})) << "the unsent keyframe still sees it";

  MapReplica plain = build();
  plain.apply(u);
  EXPECT_TRUE(plain.keyframe(K2)->T_w_c.isApprox(Pose3::Identity()));
  EXPECT_TRUE(plain.point(P3)->p_w.isApprox(point(P3).p_w));
}

// Mapping culled K2 before the correction, so the corrected map names neither K2 nor K3 (made on K2, not yet
// sent): K3 moves as K2's parent K1 moved, as mapping will move it when it arrives.
TEST(MapReplica, AnUnsentKeyframeWhoseParentWasCulledMovesWithTheParentsParent) {
  MapReplica m;
  m.add(keyframeMessage(K1, {P1}, {P1}));
  msg::KeyFrame k2 = keyframeMessage(K2, {P1, P2}, {P2});
  k2.state.parent = K1;
  m.add(k2);
  msg::KeyFrame k3 = keyframeMessage(K3, {P2, P3}, {P3});
  k3.state.parent = K2;
  k3.new_points[0].reference = K3;
  m.add(k3);
  msg::LocalMapUpdate cull;
  cull.culled_keyframes.push_back(K2);
  m.apply(cull);
  ASSERT_EQ(m.keyframe(K2), nullptr);

  msg::LocalMapUpdate u;
  u.correction = true;
  u.corrections_seen = 1;
  KeyframeState k1 = keyframe(K1, {P1});
  k1.T_w_c.translation() = Eigen::Vector3d(0, 0, 5);
  u.keyframes.push_back(k1);
  m.apply(u, true);
  EXPECT_TRUE(m.keyframe(K3)->T_w_c.isApprox(k1.T_w_c));
  EXPECT_TRUE(m.point(P3)->p_w.isApprox(k1.T_w_c * point(P3).p_w));
}

}  // namespace
}  // namespace binloop
