#include "binloop/loop/loop_detector.h"

#include <gtest/gtest.h>

#include "binloop/place/model_training.h"
#include "binloop/util/hash_random.h"
#include "support/test_support.h"

namespace binloop {
namespace {

// A route of 40 places. A place's 300 descriptors scatter (30 bits) around a place-specific descriptor, and
// places are ~128 bits apart, so a vocabulary separates them as it separates the textures of real places; a
// view of a place flips 3 more bits of each. Keyframe i sees place i and half of place i+1, so consecutive
// keyframes are covisible.
class LoopDetectorTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    HashRng rng(5);
    for (int p = 0; p < 41; ++p) {
      Desc256 centre;
      for (auto& w : centre.w) w = rng.next();
      Descriptors d(300, centre);
      for (auto& x : d) flip(x, 30, rng);
      places().push_back(d);
    }
    std::vector<Descriptors> training;
    for (const Descriptors& p : places()) training.push_back(view(p, rng));
    dir() = std::make_unique<test::TempDir>();
    TrainOptions o;
    o.k = 10;
    o.levels = 3;
    trainModel(ModelType::kHbow, training, o, *dir() / "hbow.bin");
    TrainOptions v;
    v.k = 4;
    trainModel(ModelType::kVlad, training, v, *dir() / "vlad.bin");
  }
  static void flip(Desc256& x, int bits, HashRng& rng) {
    for (int f = 0; f < bits; ++f) {
      const int bit = rng.below(256);
      x.w[bit / 64] ^= uint64_t{1} << (bit % 64);
    }
  }
  static Descriptors view(const Descriptors& place, HashRng& rng) {
    Descriptors d = place;
    for (auto& x : d) flip(x, 3, rng);
    return d;
  }
  static std::vector<Descriptors>& places() {
    static std::vector<Descriptors> p;
    return p;
  }
  static std::unique_ptr<test::TempDir>& dir() {
    static std::unique_ptr<test::TempDir> d;
    return d;
  }
  // The test's vocabulary is an hbow one (the product's default model is another).
  static LoopDetectorParams hbowParams() {
    LoopDetectorParams p;
    p.model = "hbow";
    return p;
  }
  static LoopDetector::ModelFactory factory() {
    return [](const std::string& name) {
      RecognizerOptions o;
      o.model_file = *dir() / (name + ".bin");
      return makePlaceRecognizer(name, o);
    };
  }

  msg::KeyFrame keyframe(int index, int place) {
    msg::KeyFrame kf;
    kf.id = kf.state.id = (uint64_t{1} << 56) | static_cast<uint64_t>(index + 1);
    kf.frame_index = static_cast<uint64_t>(index) * 5;
    kf.descriptors = view(places()[place], rng);
    const Descriptors next = view(places()[place + 1], rng);
    kf.descriptors.insert(kf.descriptors.end(), next.begin(), next.begin() + 150);
    if (index > 0) kf.state.covisible.push_back({idOf(index - 1), 150});
    return kf;
  }
  static SlamKeyframeId idOf(int index) { return (uint64_t{1} << 56) | static_cast<uint64_t>(index + 1); }
  static int indexOf(SlamKeyframeId id) { return static_cast<int>(counterOf(id)) - 1; }

  HashRng rng{9};
};

TEST_F(LoopDetectorTest, ARevisitIsAcceptedAfterTheConsistencyCheckAndPointsAtThePlace) {
  // The shipped 2, and ORB-SLAM2's 3: accepted at the query after that many consistent ones.
  for (int consistency : {2, 3}) {
    LoopDetectorParams p = hbowParams();
    p.consistency = consistency;
    LoopDetector d(p, factory());
    int accepted_at = -1;
    for (int i = 0; i < 40; ++i) {
      const auto out = d.process(keyframe(i, i));
      EXPECT_EQ(out.active->accepted, kNoId) << "keyframe " << i << " is no loop";
    }
    for (int i = 40; i < 48; ++i) {
      const auto out = d.process(keyframe(i, i - 30));
      EXPECT_EQ(out.active->model, "hbow");
      if (out.active->accepted != kNoId && accepted_at < 0) {
        accepted_at = i;
        EXPECT_NEAR(indexOf(out.active->accepted), i - 30, 1) << "keyframe " << i;
        // hbow's coarse words for verification: one per keypoint, the same for a place's point in both views.
        ASSERT_EQ(out.active->query_words.size(), 450u);
        ASSERT_EQ(out.active->accepted_words.size(), 450u);
        if (indexOf(out.active->accepted) == i - 30) {
          int same = 0;
          for (size_t k = 0; k < 300; ++k)
            same += out.active->query_words[k] == out.active->accepted_words[k];
          EXPECT_GT(same, 250) << "of 300 views of the same descriptors";
        }
      } else if (out.active->accepted == kNoId) {
        EXPECT_TRUE(out.active->query_words.empty());
      }
    }
    EXPECT_EQ(accepted_at, 40 + consistency) << consistency << " consistent queries before it, from 40 on";
  }
}

TEST_F(LoopDetectorTest, SwitchingModelsRebuildsTheIndexAndTakesOverAtTheNextKeyframe) {
  LoopDetector d(hbowParams(), factory());
  for (int i = 0; i < 41; ++i) d.process(keyframe(i, i < 40 ? i : 10));
  d.switchModel("vlad");
  EXPECT_EQ(d.activeModel(), "hbow") << "not before the next keyframe";
  const auto out = d.process(keyframe(41, 11));
  EXPECT_EQ(d.activeModel(), "vlad");
  EXPECT_EQ(out.active->model, "vlad");
  ASSERT_FALSE(out.active->candidates.empty()) << out.active->status << ": " << out.active->detail;
  EXPECT_NEAR(indexOf(out.active->candidates.front().id), 11, 1)
      << "the rebuilt index holds the old keyframes";
  EXPECT_EQ(d.keyframeCount(), 42u);
}

TEST_F(LoopDetectorTest, ShadowModelsAreQueriedOnTheSameKeyframesAndOnlyLogged) {
  LoopDetector d(hbowParams(), factory());
  for (int i = 0; i < 30; ++i) d.process(keyframe(i, i));
  d.setShadowModels({"vlad", "hbow"});  // the active one is not shadowed twice
  const auto out = d.process(keyframe(30, 5));
  ASSERT_EQ(out.shadow.size(), 1u);
  EXPECT_EQ(out.shadow[0]->model, "vlad");
  EXPECT_TRUE(out.shadow[0]->shadow);
  EXPECT_EQ(out.shadow[0]->query, out.active->query);
  ASSERT_FALSE(out.shadow[0]->candidates.empty()) << out.shadow[0]->status;
  EXPECT_NEAR(indexOf(out.shadow[0]->candidates.front().id), 5, 1);
}

TEST_F(LoopDetectorTest, AnUnknownModelIsRefusedAndTheRunningOneStays) {
  LoopDetector d(hbowParams(), factory());
  d.process(keyframe(0, 0));
  EXPECT_THROW(d.switchModel("nosuchmodel"), PlaceError);
  d.process(keyframe(1, 1));
  EXPECT_EQ(d.activeModel(), "hbow");
  msg::KeyFrame empty = keyframe(2, 2);
  empty.descriptors.clear();
  EXPECT_THROW(d.process(empty), std::invalid_argument);
}

// A restarted detector gets the map's keyframes again from local mapping, marked resent: they are indexed,
// never queried (no old revisit is proposed again), and the next new keyframe finds them.
TEST_F(LoopDetectorTest, ResentKeyframesAreIndexedWithoutQueries) {
  LoopDetector d(hbowParams(), factory());
  for (int i = 0; i < 40; ++i) {
    msg::KeyFrame kf = keyframe(i, i < 35 ? i : i - 30);  // 35-39 revisit places 5-9
    kf.resent = true;
    const auto out = d.process(kf);
    EXPECT_FALSE(out.active) << "resent keyframe " << i << " was queried";
    EXPECT_TRUE(out.shadow.empty());
  }
  EXPECT_EQ(d.keyframeCount(), 40u);
  const auto out = d.process(keyframe(40, 12));
  ASSERT_TRUE(out.active);
  ASSERT_FALSE(out.active->candidates.empty()) << out.active->status << ": " << out.active->detail;
  EXPECT_NEAR(indexOf(out.active->candidates.front().id), 12, 1) << "the resent keyframes are in the index";
}

TEST_F(LoopDetectorTest, RecentKeyframesAreNeverCandidates) {
  LoopDetectorParams p = hbowParams();
  p.ignore_recent = 20;
  LoopDetector d(p, factory());
  for (int i = 0; i < 30; ++i) {
    const auto out = d.process(keyframe(i, i < 25 ? i : 15));  // 25-29 come back to place 15: 10 back
    for (const auto& c : out.active->candidates) EXPECT_LT(indexOf(c.id), i - 20) << "keyframe " << i;
  }
}

}  // namespace
}  // namespace binloop
