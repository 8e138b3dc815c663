// MapStore: the map bookkeeping local mapping and tracking's replica share (include/binloop/map/map_store.h).
#include "binloop/map/map_store.h"

#include <gtest/gtest.h>

#include "support/test_support.h"

namespace binloop {
namespace {

struct Record {  // a holder's richer keyframe record, as local mapping keeps one
  msg::KeyframeState state;
};
using Store = MapStore<Record, msg::MapPoint>;

constexpr SlamKeyframeId K1 = 1, K2 = 2, K3 = 3, K4 = 4;
constexpr MapPointId P1 = 101, P2 = 102, P3 = 103;

void addKeyframe(Store& s, SlamKeyframeId id, SlamKeyframeId parent, double x) {
  Record& r = s.keyframes()[id];
  r.state.id = id;
  r.state.parent = parent;
  r.state.T_w_c = Pose3(Eigen::Translation3d(x, 0, 0));
}

// A point fused into one that was fused in turn resolves to the last; a culled point resolves to nothing,
// though an id fused into it still follows the chain to it.
TEST(MapStore, AnIdResolvesThroughEveryFusionToAHeldPoint) {
  Store s;
  s.points()[P3].id = P3;
  s.recordFusion(P1, P2);
  s.recordFusion(P2, P3);
  EXPECT_TRUE(s.wasFused(P1));
  EXPECT_FALSE(s.wasFused(P3));
  EXPECT_EQ(s.resolve(P1), P3);
  EXPECT_EQ(s.resolve(P3), P3);
  s.points().erase(P3);
  EXPECT_EQ(s.followed(P1), P3);
  EXPECT_EQ(s.resolve(P1), kNoId);
  EXPECT_EQ(s.resolve(999), kNoId);
}

// K1 <- K2 <- K3 <- K4 with K2 and K3 culled: K4 climbs through both to K1; the culled keep their parent
// and their pose relative to it while the parent is held (K2's), identity once it is not (K3's).
TEST(MapStore, TheTreeIsClimbedThroughCulledKeyframes) {
  Store s;
  addKeyframe(s, K1, kNoId, 0);
  addKeyframe(s, K2, K1, 1);
  addKeyframe(s, K3, K2, 2.5);
  addKeyframe(s, K4, K3, 3);
  s.cull(K2);
  s.cull(K3);
  s.cull(99);  // never held: nothing happens
  EXPECT_EQ(s.keyframes().size(), 2u);
  EXPECT_TRUE(s.culled(K2)->T_parent_kf.isApprox(Pose3(Eigen::Translation3d(1, 0, 0))));
  EXPECT_TRUE(s.culled(K3)->T_parent_kf.isApprox(Pose3::Identity()));
  EXPECT_TRUE(s.knows(K2));
  EXPECT_FALSE(s.knows(99));
  EXPECT_EQ(s.parentOf(K4), K3);
  EXPECT_EQ(s.parentOf(K3), K2);
  EXPECT_EQ(s.culledParent(K4), kNoId);
  EXPECT_EQ(s.parentOf(99), kNoId);
  auto held = [&](SlamKeyframeId k) { return s.keyframes().count(k) > 0; };
  EXPECT_EQ(s.firstAncestor(K3, held), K1);
  EXPECT_EQ(s.firstAncestor(K4, held), K4);
  EXPECT_EQ(s.firstAncestor(K4, [](SlamKeyframeId) { return false; }), kNoId);
}

// The fusions and culled keyframes go through a state file and come back the same, in id order.
TEST(MapStore, FusionsAndCulledKeyframesSurviveAStateFile) {
  Store s;
  s.recordFusion(P2, P3);
  s.recordFusion(P1, P3);
  s.recordCulled(K3, K1, Pose3(Eigen::Translation3d(0, 2, 0)));
  s.recordCulled(K2, K1, Pose3(Eigen::Translation3d(0, 1, 0)));
  struct Saved {
    const Store* from = nullptr;
    Store* to = nullptr;
    void save(StateWriter& w) const {
      from->saveFusions(w);
      from->saveCulled(w);
    }
    void load(StateReader& r) {
      to->loadFusions(r, "fused points");
      to->loadCulled(r);
      r.expectEnd();
    }
  };
  test::TempDir dir;
  const std::string path = dir / "store.state";
  saveStateFile(Saved{&s, nullptr}, path, "store", 7);
  Store back;
  Saved into{nullptr, &back};
  EXPECT_EQ(loadStateFile(into, path, "store"), 7u);
  EXPECT_EQ(back.fusions(), s.fusions());
  ASSERT_EQ(back.culledKeyframes().size(), 2u);
  EXPECT_EQ(back.culledParent(K3), K1);
  EXPECT_TRUE(back.culled(K2)->T_parent_kf.isApprox(s.culled(K2)->T_parent_kf));
  const std::string again = dir / "again.state";
  saveStateFile(Saved{&back, nullptr}, again, "store", 7);
  EXPECT_EQ(test::readText(path), test::readText(again));
}

}  // namespace
}  // namespace binloop
