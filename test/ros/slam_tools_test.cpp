// run and eval-slam as a user runs them: the loop log and summary run writes with a detector on, the table
// eval-slam writes, and one clear line for bad options. On the real 11-frame sample (no revisit: these check
// the tools' outputs; loop closing itself is tested in test/core/pipeline/loop_closing_pipeline_test.cpp).
#include <fstream>
#include <sstream>

#include "support/test_support.h"

namespace {
binloop::test::CommandResult tool(const std::string& name, const std::string& args) {
  return binloop::test::runCommand(std::string(BINLOOP_TOOL_DIR) + "/" + name + " " + args);
}
int lines(const std::string& s) {
  int n = 0;
  for (char c : s) n += c == '\n';
  return n;
}
const std::string kVocab = std::string(BINLOOP_ROOT_DIR) + "/vocab/kitti08";
}  // namespace

TEST(SlamTools, RunWithADetectorWritesTheLoopLogAndCounts) {
  const std::string seq = binloop::test::sharedData("kitti/sample_00");
  BINLOOP_REQUIRE_DATA(seq);
  BINLOOP_REQUIRE_DATA(kVocab + "/vladpq.bin");
  binloop::test::TempDir tmp;
  const auto r = tool("run", seq + " --out " + (tmp / "out") + " --lockstep --detector vladpq --vocab-dir " +
                                 kVocab + " --shadow vlad --reloc-vocab none");
  ASSERT_EQ(r.code, 0) << r.out;
  const std::string log = binloop::test::readText(tmp / "out/loops.csv");
  ASSERT_EQ(log.rfind("keyframe,frame,model,shadow,status,candidates,", 0), 0u) << log;
  const std::string summary = binloop::test::readText(tmp / "out/summary.json");
  // One active and one shadow row per keyframe.
  const auto pos = summary.find("\"keyframes_made\": ");
  ASSERT_NE(pos, std::string::npos) << summary;
  const int keyframes = std::stoi(summary.substr(pos + 18));
  EXPECT_GT(keyframes, 1);
  EXPECT_EQ(lines(log), 1 + 2 * keyframes) << log;
  EXPECT_NE(log.find(",vladpq,0,"), std::string::npos);
  EXPECT_NE(log.find(",vlad,1,"), std::string::npos);
  // The live trajectory (each frame as tracked at the time) beside the final one, a pose per frame.
  const int frames = lines(binloop::test::readText(tmp / "out/trajectory.kitti.txt"));
  EXPECT_EQ(frames, 11);
  EXPECT_EQ(lines(binloop::test::readText(tmp / "out/live.kitti.txt")), frames);
  EXPECT_EQ(lines(binloop::test::readText(tmp / "out/live.tum.txt")), frames);
  for (const char* key : {"\"detector\": \"vladpq\"", "\"loops_accepted\": 0", "\"loop_queries\": ",
                          "\"detect_vladpq_query_ms_median\": ", "\"detect_vlad_shadow_ms_median\": "})
    EXPECT_NE(summary.find(key), std::string::npos) << key << " missing from\n" << summary;
}

// A user runs the tools from any folder: the default detector's model and the relocalisation vocabulary
// are the package's shipped files, not paths relative to where the user stands.
TEST(SlamTools, DefaultsAreThePackagesShippedFilesFromAnyFolder) {
  const std::string seq = binloop::test::sharedData("kitti/sample_00");
  BINLOOP_REQUIRE_DATA(seq);
  binloop::test::TempDir tmp;
  const auto r = binloop::test::runCommand("cd " + tmp.path() + " && " + std::string(BINLOOP_TOOL_DIR) +
                                           "/run " + seq + " --out out --lockstep");
  ASSERT_EQ(r.code, 0) << r.out;
  const std::string summary = binloop::test::readText(tmp / "out/summary.json");
  EXPECT_NE(summary.find("\"detector\": \"hmvlad\""), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"reloc_vocab\": \"" + kVocab + "/hbow_k8l5.bin\""), std::string::npos) << summary;
  // hbow's vocabulary is not shipped: the error says how to make it.
  const auto hbow =
      tool("run", seq + " --out " + (tmp / "h") + " --detector hbow --vocab-dir " + (tmp / "empty"));
  EXPECT_NE(hbow.code, 0);
  EXPECT_NE(
      hbow.out.find((tmp / "empty") + "/hbow.bin: not found: the k=10, L=6 hbow vocabulary (26 MB) is not "
                                      "shipped; vocab/make_vocab.sh hbow makes it"),
      std::string::npos)
      << hbow.out;
}

// A real camera turns on ORB's learned BRIEF tests in its config and nothing else: the default model folder
// and relocalisation vocabulary follow them to the shipped photo set, which loads (with the warning that it
// was trained on scaled pictures) instead of the Gaussian set being refused.
TEST(SlamTools, LearnedTestsPickThePhotoVocabulariesByThemselves) {
  const std::string seq = binloop::test::sharedData("kitti/sample_00");
  BINLOOP_REQUIRE_DATA(seq);
  const std::string photos = std::string(BINLOOP_ROOT_DIR) + "/vocab/photos";
  binloop::test::TempDir tmp;
  std::ofstream(tmp / "learned.yaml") << "%YAML:1.0\norb:\n  learned_pattern: 1\n";
  const auto r = binloop::test::runCommand("cd " + tmp.path() + " && " + std::string(BINLOOP_TOOL_DIR) +
                                           "/run " + seq + " --out out --lockstep --config learned.yaml");
  ASSERT_EQ(r.code, 0) << r.out;
  const std::string summary = binloop::test::readText(tmp / "out/summary.json");
  EXPECT_NE(summary.find("\"reloc_vocab\": \"" + photos + "/hbow_k8l5.bin\""), std::string::npos) << summary;
  EXPECT_NE(r.out.find(photos + "/hmvlad.bin: trained on images scaled to a longer side <= 1024 px"),
            std::string::npos)
      << r.out;
  // The Gaussian set named by hand is still refused, naming the difference.
  const auto kitti = tool("run", seq + " --out " + (tmp / "k") + " --lockstep --config " +
                                     (tmp / "learned.yaml") + " --reloc-vocab " + kVocab + "/hbow_k8l5.bin");
  EXPECT_NE(kitti.code, 0);
  EXPECT_NE(kitti.out.find(kVocab + "/hbow_k8l5.bin: trained on descriptors of"), std::string::npos)
      << kitti.out;
}

TEST(SlamTools, BadLoopOptionsAreOneClearLine) {
  const std::string seq = binloop::test::sharedData("kitti/sample_00");
  BINLOOP_REQUIRE_DATA(seq);
  binloop::test::TempDir tmp;
  const auto unknown = tool("run", seq + " --out " + (tmp / "a") + " --detector sift");
  EXPECT_NE(unknown.code, 0);
  EXPECT_NE(unknown.out.find("--detector 'sift': not one of hbow, fabmap, vlad, hmvlad, vladpq"),
            std::string::npos)
      << unknown.out;
  const auto sw = tool("run", seq + " --out " + (tmp / "b") + " --detector vladpq --vocab-dir " + kVocab +
                                  " --switch-detector-at 500");
  EXPECT_NE(sw.code, 0);
  EXPECT_NE(sw.out.find("--switch-detector-at '500': expected KF:model"), std::string::npos) << sw.out;
  const auto missing =
      tool("run", seq + " --out " + (tmp / "c") + " --detector vladpq --vocab-dir " + (tmp / "none"));
  EXPECT_NE(missing.code, 0);
  EXPECT_NE(missing.out.find("vladpq.bin"), std::string::npos) << missing.out;
  const auto eval =
      tool("eval-slam", "--sequence " + seq + " --out " + (tmp / "d") + " --detectors vladpq,sift");
  EXPECT_NE(eval.code, 0);
  EXPECT_NE(eval.out.find("unknown detector 'sift'"), std::string::npos) << eval.out;
}

TEST(SlamTools, EvalSlamScoresEveryDetectorInOneTable) {
  const std::string seq = binloop::test::sharedData("kitti/sample_00");
  BINLOOP_REQUIRE_DATA(seq);
  BINLOOP_REQUIRE_DATA(kVocab + "/vladpq.bin");
  binloop::test::TempDir tmp;
  binloop::test::writeText(tmp / "gt.txt",
                           "# no revisit in 11 frames; one made-up pair so there is a segment\n10 0\n");
  const auto r = tool("eval-slam", "--sequence " + seq + " --out " + (tmp / "out") +
                                       " --detectors vladpq,none --jobs 1" + " --lockstep --loop-gt " +
                                       (tmp / "gt.txt") + " --run-args \"--reloc-vocab none --vocab-dir " +
                                       kVocab + "\"");
  ASSERT_EQ(r.code, 0) << r.out;
  const std::string table = binloop::test::readText(tmp / "out/summary.csv");
  EXPECT_EQ(table.rfind("model,ate_m,t_rel_pct,r_rel_deg_100m,loops_accepted,loops_correct,loops_wrong_pose,"
                        "segments_closed,",
                        0),
            0u)
      << table;
  EXPECT_NE(table.find("\nvladpq,"), std::string::npos) << table;
  EXPECT_NE(table.find("\nnone,"), std::string::npos) << table;
  EXPECT_NE(table.find(",0,0,0,0/1,"), std::string::npos)
      << "no loop in 11 frames: nothing accepted, the segment open\n"
      << table;
  EXPECT_TRUE(binloop::test::exists(tmp / "out/trajectories.png"));
}

// --rate paces a threaded run by the sequence's clock (sample_00: 11 frames, 1.04 s), so the run cannot take
// less than the sequence lasts; a bad factor, or one with --lockstep, is one clear line.
TEST(SlamTools, RunAtARatePacesFramesByTheSequenceClock) {
  const std::string seq = binloop::test::sharedData("kitti/sample_00");
  BINLOOP_REQUIRE_DATA(seq);
  binloop::test::TempDir tmp;
  const auto r =
      tool("run", seq + " --out " + (tmp / "out") + " --detector none --rate 1 --reloc-vocab none");
  ASSERT_EQ(r.code, 0) << r.out;
  const std::string summary = binloop::test::readText(tmp / "out/summary.json");
  EXPECT_NE(summary.find("\"rate\": 1,"), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"max_lag_s\": "), std::string::npos) << summary;
  const auto wall = summary.find("\"wall_s\": ");
  ASSERT_NE(wall, std::string::npos) << summary;
  std::ifstream times(seq + "/times.txt");
  double t, first = -1, last = 0;
  while (times >> t) {
    if (first < 0) first = t;
    last = t;
  }
  EXPECT_GE(std::stod(summary.substr(wall + 10)), 0.95 * (last - first)) << summary;

  const auto both = tool("run", seq + " --out " + (tmp / "b") + " --rate 1 --lockstep");
  EXPECT_NE(both.code, 0);
  EXPECT_NE(both.out.find("--rate paces a threaded run"), std::string::npos) << both.out;
  const auto bad = tool("run", seq + " --out " + (tmp / "c") + " --rate -2");
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.out.find("--rate -2: 0 (flat out) or a factor up to 1000"), std::string::npos) << bad.out;
}
