// Loading the SLAM's settings (include/binloop/pipeline/slam_config.h): config/kitti.yaml is the defaults,
// and every mistake in a file is a ConfigError that names the file and the key.
#include "binloop/pipeline/slam_config.h"

#include <gtest/gtest.h>

#include <fstream>
#include <set>
#include <sstream>

#include "support/test_support.h"

namespace binloop {
namespace {

using test::TempDir;

// BINLOOP_ROOT_DIR comes from cmake/binloop_core.cmake (binloop_test_support's compile definitions).
const std::string kKittiYaml = std::string(BINLOOP_ROOT_DIR) + "/config/kitti.yaml";

/// A config file in `dir` with the YAML header and `body`.
std::string configFile(const TempDir& dir, const std::string& body, const std::string& name = "slam.yaml") {
  const std::string path = dir / name;
  test::writeText(path, "%YAML:1.0\n" + body);
  return path;
}

TEST(SlamConfig, KittiYamlEqualsTheDefaults) {
  ASSERT_TRUE(test::exists(kKittiYaml)) << kKittiYaml;
  const SlamConfig loaded = loadSlamConfig(kKittiYaml);
  const SlamConfig defaults;
  EXPECT_EQ(describe(loaded), describe(defaults));
  // Settings describe() does not list.
  EXPECT_TRUE(loaded.mapper.stereo == defaults.mapper.stereo);
  EXPECT_TRUE(loaded.tracker.orb == defaults.tracker.orb);
  EXPECT_TRUE(loaded.tracker.stereo == defaults.tracker.stereo);
}

TEST(SlamConfig, DescribeListsEverySettingOnce) {
  const std::string d = describe(SlamConfig{});
  EXPECT_NE(d.find("orb.features: 2000\n"), std::string::npos) << d;
  EXPECT_NE(d.find("orb.scale_factor: 1.2\n"), std::string::npos) << d;
  EXPECT_NE(d.find("mapping.fuse: 1\n"), std::string::npos) << d;
  EXPECT_NE(d.find("tracking.keyframe_ref_ratio: 0.75\n"), std::string::npos) << d;
  // Every key of kitti.yaml (each documented there) is described, and nothing else.
  std::set<std::string> described, documented;
  std::istringstream lines(d);
  std::string line;
  while (std::getline(lines, line)) {
    ASSERT_NE(line.find(": "), std::string::npos) << line;
    EXPECT_TRUE(described.insert(line.substr(0, line.find(": "))).second) << "twice: " << line;
  }
  std::ifstream yaml(kKittiYaml);
  ASSERT_TRUE(yaml) << kKittiYaml;
  std::string section;
  while (std::getline(yaml, line)) {
    if (line.empty() || line[0] == '#' || line[0] == '%') continue;
    const size_t colon = line.find(':');
    if (colon == std::string::npos) continue;
    if (line[0] != ' ') {
      section = line.substr(0, colon);
    } else {
      const size_t start = line.find_first_not_of(' ');
      if (line[start] != '#') documented.insert(section + "." + line.substr(start, colon - start));
    }
  }
  EXPECT_EQ(described, documented);
  EXPECT_GT(described.size(), 30u);  // the set comparison above is the real check
}

TEST(SlamConfig, KeysGivenOverrideTheRestKeepDefaults) {
  TempDir dir;
  const std::string path = configFile(dir,
                                      "orb:\n  features: 1000\n  scale_factor: 1.5\n"
                                      "stereo:\n  close_depth_baselines: 35.5\n"
                                      "tracking:\n  keyframe_ref_ratio: 0.5\n"
                                      "mapping:\n  fuse: 0\n  local_ba_max_keyframes: 12\n");
  const SlamConfig c = loadSlamConfig(path);
  const SlamConfig d;
  EXPECT_EQ(c.tracker.orb.features, 1000);
  EXPECT_FLOAT_EQ(c.tracker.orb.scale_factor, 1.5f);
  EXPECT_EQ(c.tracker.orb.levels, d.tracker.orb.levels);
  EXPECT_DOUBLE_EQ(c.tracker.stereo.close_depth_baselines, 35.5);
  // The mapper's "close" is the stereo matcher's.
  EXPECT_DOUBLE_EQ(c.mapper.stereo.close_depth_baselines, 35.5);
  EXPECT_FLOAT_EQ(c.tracker.keyframe_ref_ratio, 0.5f);
  EXPECT_EQ(c.tracker.min_inliers, d.tracker.min_inliers);
  EXPECT_FALSE(c.mapper.fuse);
  EXPECT_TRUE(c.mapper.local_ba);
  EXPECT_EQ(c.mapper.local_ba_max_keyframes, 12);
}

// The place models' thresholds are loop detection's keys; the runner and the nodelet hand them to the
// factory.
TEST(SlamConfig, ModelThresholdsAreLoopDetectionKeys) {
  TempDir dir;
  const SlamConfig c = loadSlamConfig(
      configFile(dir,
                 "loop_detection:\n  vladpq_shared_slack: 2\n  hbow_min_bar: 0.01\n  fabmap_l2_offset: 0.1\n"
                 "  vlad_reference_rank: 1\n"));
  EXPECT_EQ(c.models.vladpq_shared_slack, 2);
  EXPECT_EQ(c.models.vlad_reference_rank, 1);
  EXPECT_DOUBLE_EQ(c.models.hbow_min_bar, 0.01);
  EXPECT_DOUBLE_EQ(c.models.fabmap_l2_offset, 0.1);
  EXPECT_EQ(c.detector.consistency, SlamConfig{}.detector.consistency);
  EXPECT_THROW(loadSlamConfig(configFile(dir, "loop_detection:\n  vladpq_shared_slack: -1\n", "neg.yaml")),
               ConfigError);
  EXPECT_THROW(loadSlamConfig(configFile(dir, "loop_detection:\n  vlad_reference_rank: 0\n", "zero.yaml")),
               ConfigError);
}

TEST(SlamConfig, SectionsMayBeLeftOut) {
  TempDir dir;
  const SlamConfig c = loadSlamConfig(configFile(dir, "mapping:\n  cull_keyframes: 0\n"));
  EXPECT_FALSE(c.mapper.cull_keyframes);
  SlamConfig expected;
  expected.mapper.cull_keyframes = false;
  EXPECT_EQ(describe(c), describe(expected));
}

TEST(SlamConfig, MissingFileNamesIt) {
  TempDir dir;
  const std::string path = dir / "nope.yaml";
  EXPECT_THROW_WITH(loadSlamConfig(path), ConfigError, path + ": no such file");
  // A folder is not a config file either.
  EXPECT_THROW_WITH(loadSlamConfig(dir.path()), ConfigError, dir.path());
}

TEST(SlamConfig, UnknownSectionNamesFileAndSection) {
  TempDir dir;
  const std::string path = configFile(dir, "orb:\n  features: 1000\nmaping:\n  fuse: 0\n");
  EXPECT_THROW_WITH(loadSlamConfig(path), ConfigError, path + ": unknown section 'maping'");
  EXPECT_THROW_WITH(
      loadSlamConfig(path), ConfigError,
      "known: loop_closing, loop_detection, mapping, orb, pipeline, recovery, stereo, tracking");
}

TEST(SlamConfig, RecoveryKeysReachTheTracker) {
  TempDir dir;
  const std::string path = configFile(dir,
                                      "recovery:\n  rotation_first: 0\n  rotation_min_distance_m: 30\n"
                                      "  pose_max_turn_deg: 3.5\n  reloc_keyframes: 7\n");
  const SlamConfig c = loadSlamConfig(path);
  EXPECT_FALSE(c.tracker.recover_rotation_first);
  EXPECT_EQ(c.tracker.rotation_search.min_distance_m, 30);
  EXPECT_EQ(c.tracker.far_pose.max_turn_deg, 3.5);
  EXPECT_EQ(c.tracker.reloc_keyframes, 7);
  EXPECT_EQ(c.tracker.far_pose.iterations, SlamConfig{}.tracker.far_pose.iterations);
  EXPECT_THROW_WITH(loadSlamConfig(configFile(dir, "recovery:\n  rotation_iterations: 0\n", "bad.yaml")),
                    ConfigError, "recovery.rotation_iterations = 0.000000 is out of range (at least 1");
}

// The wait for mapping is the offline pipeline's, not the tracker's: it has its own section, and the file
// leaves the mode (the runner's option) alone.
TEST(SlamConfig, PipelineSectionReachesThePipeline) {
  TempDir dir;
  const SlamConfig c = loadSlamConfig(configFile(dir, "pipeline:\n  wait_for_mapping_ms: 150\n"));
  EXPECT_EQ(c.pipeline.wait_for_mapping_ms, 150);
  EXPECT_EQ(c.pipeline.mode, PipelineMode::kLockStep);
  EXPECT_EQ(SlamConfig{}.pipeline.wait_for_mapping_ms, 0) << "the default: never wait";
  EXPECT_THROW_WITH(loadSlamConfig(configFile(dir, "tracking:\n  wait_for_mapping_ms: 150\n", "old.yaml")),
                    ConfigError, "unknown key 'tracking.wait_for_mapping_ms'");
}

TEST(SlamConfig, UnknownKeyNamesFileAndKey) {
  TempDir dir;
  const std::string path = configFile(dir, "orb:\n  featurs: 1000\n");
  EXPECT_THROW_WITH(loadSlamConfig(path), ConfigError, path + ": unknown key 'orb.featurs'");
  EXPECT_THROW_WITH(loadSlamConfig(path), ConfigError, "features");  // the known keys are listed
  // A key of another section is unknown in this one.
  const std::string other = configFile(dir, "tracking:\n  fuse: 1\n", "other.yaml");
  EXPECT_THROW_WITH(loadSlamConfig(other), ConfigError, other + ": unknown key 'tracking.fuse'");
}

TEST(SlamConfig, NonNumericValueNamesFileAndKey) {
  TempDir dir;
  for (const char* value : {"many", "\"12\"", "[1, 2]", "{a: 1}"}) {
    const std::string path = configFile(dir, std::string("orb:\n  features: ") + value + "\n");
    EXPECT_THROW_WITH(loadSlamConfig(path), ConfigError, path + ": orb.features must be a number");
  }
}

TEST(SlamConfig, OutOfRangeValueNamesFileAndKey) {
  TempDir dir;
  std::string path = configFile(dir, "orb:\n  features: 0\n");
  EXPECT_THROW_WITH(loadSlamConfig(path), ConfigError, path + ": orb.features = 0");
  EXPECT_THROW_WITH(loadSlamConfig(path), ConfigError, "out of range (at least 1");
  path = configFile(dir, "orb:\n  scale_factor: 1.0\n");
  EXPECT_THROW_WITH(loadSlamConfig(path), ConfigError, path + ": orb.scale_factor");
  path = configFile(dir, "tracking:\n  min_inliers: -5\n");
  EXPECT_THROW_WITH(loadSlamConfig(path), ConfigError, path + ": tracking.min_inliers");
  path = configFile(dir, "stereo:\n  close_depth_baselines: .inf\n");
  EXPECT_THROW_WITH(loadSlamConfig(path), ConfigError, path + ": stereo.close_depth_baselines");
  path = configFile(dir, "stereo:\n  close_depth_baselines: .nan\n");
  EXPECT_THROW_WITH(loadSlamConfig(path), ConfigError, path + ": stereo.close_depth_baselines");
  // The smallest value is accepted.
  const SlamConfig c = loadSlamConfig(configFile(dir, "orb:\n  features: 1\nstereo:\n  max_hamming: 0\n"));
  EXPECT_EQ(c.tracker.orb.features, 1);
  EXPECT_EQ(c.tracker.stereo.max_hamming, 0);
}

TEST(SlamConfig, NonIntegerForAnIntKeyNamesFileAndKey) {
  TempDir dir;
  const std::string path = configFile(dir, "orb:\n  levels: 2.5\n");
  EXPECT_THROW_WITH(loadSlamConfig(path), ConfigError, path + ": orb.levels must be a whole number");
  // 8.0 is a whole number.
  EXPECT_EQ(loadSlamConfig(configFile(dir, "orb:\n  levels: 8.0\n", "b.yaml")).tracker.orb.levels, 8);
  // Flags are 0 or 1.
  const std::string flag = configFile(dir, "mapping:\n  fuse: 0.5\n", "c.yaml");
  EXPECT_THROW_WITH(loadSlamConfig(flag), ConfigError, flag + ": mapping.fuse must be a whole number");
  const std::string two = configFile(dir, "mapping:\n  local_ba: 2\n", "d.yaml");
  EXPECT_THROW_WITH(loadSlamConfig(two), ConfigError, two + ": mapping.local_ba must be 0 or 1");
}

TEST(SlamConfig, LearnedPatternChoosesTheBriefTests) {
  TempDir dir;
  EXPECT_EQ(loadSlamConfig(configFile(dir, "orb:\n  learned_pattern: 0\n")).tracker.orb.pattern,
            BriefPatternKind::kGaussian);
  EXPECT_EQ(loadSlamConfig(configFile(dir, "orb:\n  learned_pattern: 1\n", "b.yaml")).tracker.orb.pattern,
            BriefPatternKind::kOrbLearned);
  EXPECT_EQ(SlamConfig{}.tracker.orb.pattern, BriefPatternKind::kGaussian) << "the default";
  const std::string two = configFile(dir, "orb:\n  learned_pattern: 2\n", "c.yaml");
  EXPECT_THROW_WITH(loadSlamConfig(two), ConfigError, two + ": orb.learned_pattern must be 0 or 1");
  const std::string half = configFile(dir, "orb:\n  learned_pattern: 0.5\n", "d.yaml");
  EXPECT_THROW_WITH(loadSlamConfig(half), ConfigError, half + ": orb.learned_pattern must be a whole number");
  EXPECT_NE(describe(loadSlamConfig(configFile(dir, "orb:\n  learned_pattern: 1\n", "e.yaml")))
                .find("orb.learned_pattern: 1"),
            std::string::npos);
}

TEST(SlamConfig, CullCountChoosesHowSightingsCount) {
  TempDir dir;
  using Count = LocalMapperParams::CullCount;
  EXPECT_EQ(SlamConfig{}.mapper.cull_count, Count::kCloseStereoTwice) << "the default";
  int n = 0;
  for (const auto& [value, count] :
       {std::pair{"0", Count::kKeyframes}, {"1", Count::kStereoTwice}, {"2", Count::kCloseStereoTwice}}) {
    const std::string path = configFile(dir, std::string("mapping:\n  cull_count: ") + value + "\n",
                                        "ok" + std::to_string(n++) + ".yaml");
    const SlamConfig c = loadSlamConfig(path);
    EXPECT_EQ(c.mapper.cull_count, count) << value;
    EXPECT_NE(describe(c).find(std::string("mapping.cull_count: ") + value), std::string::npos) << value;
  }
  const std::string three = configFile(dir, "mapping:\n  cull_count: 3\n", "three.yaml");
  EXPECT_THROW_WITH(loadSlamConfig(three), ConfigError, three + ": mapping.cull_count must be 0, 1 or 2");
  const std::string half = configFile(dir, "mapping:\n  cull_count: 1.5\n", "half.yaml");
  EXPECT_THROW_WITH(loadSlamConfig(half), ConfigError, half + ": mapping.cull_count must be a whole number");
  // The two flags it replaced are unknown keys now, not silently ignored.
  const std::string old = configFile(dir, "mapping:\n  cull_stereo_counts_twice: 1\n", "old.yaml");
  EXPECT_THROW(loadSlamConfig(old), ConfigError);
}

// Beyond INT_MAX a value used to wrap (OpenCV's YAML reader wraps integer literals itself, and a cast
// wrapped real ones), so a typo of a few digits became a negative or arbitrary setting.
TEST(SlamConfig, IntValueBeyondIntRangeIsOutOfRange) {
  TempDir dir;
  int n = 0;
  for (const char* value : {"3e9", "3000000000.0", "99999999999"}) {
    const std::string path = configFile(dir, std::string("orb:\n  features: ") + value + "\n",
                                        "big" + std::to_string(n++) + ".yaml");
    SCOPED_TRACE(value);
    EXPECT_THROW_WITH(loadSlamConfig(path), ConfigError, path + ": orb.features");
  }
}

TEST(SlamConfig, MinFastAboveIniFastNamesFileAndKey) {
  TempDir dir;
  const std::string path = configFile(dir, "orb:\n  ini_fast: 5\n  min_fast: 9\n");
  EXPECT_THROW_WITH(loadSlamConfig(path), ConfigError, path + ": orb.min_fast must not exceed orb.ini_fast");
  // Against the default min_fast (7) as well.
  const std::string low = configFile(dir, "orb:\n  ini_fast: 5\n", "low.yaml");
  EXPECT_THROW_WITH(loadSlamConfig(low), ConfigError, low + ": orb.min_fast");
  // Equal is fine.
  const SlamConfig c = loadSlamConfig(configFile(dir, "orb:\n  ini_fast: 9\n  min_fast: 9\n", "eq.yaml"));
  EXPECT_EQ(c.tracker.orb.min_fast, 9);
  EXPECT_EQ(c.tracker.orb.ini_fast, 9);
}

TEST(SlamConfig, MalformedFilesNameTheFile) {
  TempDir dir;
  const std::string broken = configFile(dir, "orb:\n  features: [1, 2\n", "broken.yaml");
  EXPECT_THROW_WITH(loadSlamConfig(broken), ConfigError, broken);
  const std::string scalar = configFile(dir, "orb: 5\n", "scalar.yaml");
  EXPECT_THROW_WITH(loadSlamConfig(scalar), ConfigError,
                    scalar + ": section 'orb' must hold key: value lines");
}

}  // namespace
}  // namespace binloop
