// eval-loops as a user runs it: the summary it writes for a real image pair, and one clear line for bad
// input.
#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "support/test_support.h"

namespace {
binloop::test::CommandResult run(const std::string& args) {
  return binloop::test::runCommand(std::string(BINLOOP_TOOL_DIR) + "/eval-loops " + args);
}
/// A VLAD model trained on `images` with `options` (extractor settings), written to `out`.
binloop::test::CommandResult trainVlad(const std::string& images, const std::string& options,
                                       const std::string& out) {
  return binloop::test::runCommand(std::string(BINLOOP_TOOL_DIR) + "/train vlad --images " + images + " " +
                                   options + " --out " + out);
}
/// A CSV file's rows, each split at its commas (the tools quote nothing).
std::vector<std::vector<std::string>> csvRows(const std::string& path) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream text(binloop::test::readText(path));
  for (std::string line; std::getline(text, line);) {
    std::istringstream cells(line);
    rows.emplace_back();
    for (std::string cell; std::getline(cells, cell, ',');) rows.back().push_back(cell);
  }
  return rows;
}
}  // namespace

// TUM desk 1 and 10 (indices 0 and 9) view the same desk. The tracked kitti08 VLAD-family models are
// street-trained, so this checks the tool's outputs, not the models' accuracy on desks.
TEST(EvalLoopsTool, WritesSummaryCurvesAndQueriesForAPlainImageFolder) {
  const std::string desk = binloop::test::sharedData("tum_desk");
  BINLOOP_REQUIRE_DATA(desk);
  const std::string vocab = std::string(BINLOOP_ROOT_DIR) + "/vocab/kitti08";
  BINLOOP_REQUIRE_DATA(vocab + "/vlad.bin");
  binloop::test::TempDir tmp;
  binloop::test::writeText(tmp / "gt.txt", "# desk 10 revisits desk 1\n9 0\n");
  const auto r =
      run("--sequence " + desk + " --gt " + (tmp / "gt.txt") + " --models vlad,vladpq --vocab-dir " + vocab +
          " --window 0 --reference 1 --consistency 2 --out " + (tmp / "out"));
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("10 images, 10 keyframes (step 1), 1 keyframes with a findable loop in 1 segments"),
            std::string::npos)
      << r.out;
  const std::string summary = binloop::test::readText(tmp / "out/summary.csv");
  EXPECT_EQ(summary.rfind("model,r_at_100p,auc,signature_ms_median,query_ms_median,bytes_per_kf,", 0), 0u)
      << summary;
  for (const char* row : {"\nvlad,", "\nvlad+c2,", "\nvladpq,", "\nvladpq+c2,"})
    EXPECT_NE(summary.find(row), std::string::npos) << row << " missing from\n" << summary;
  for (const char* f : {"pr.png", "pr_vlad.csv", "pr_vlad+c2.csv", "queries_vlad.csv", "queries_vladpq.csv"})
    EXPECT_TRUE(binloop::test::exists(tmp / ("out/" + std::string(f)))) << f;
  // Ten queries, one line each, after the header.
  const std::string q = binloop::test::readText(tmp / "out/queries_vlad.csv");
  EXPECT_EQ(std::count(q.begin(), q.end(), '\n'), 11) << q;
}

TEST(EvalLoopsTool, BadInputGivesOneClearLine) {
  const std::string desk = binloop::test::sharedData("tum_desk");
  BINLOOP_REQUIRE_DATA(desk);
  binloop::test::TempDir tmp;
  const auto no_gt = run("--sequence " + desk + " --out " + (tmp / "o"));
  EXPECT_EQ(no_gt.code, 2) << no_gt.out;
  EXPECT_NE(no_gt.out.find("eval-loops: --gt is required when there are no poses for every image"),
            std::string::npos)
      << no_gt.out;
  binloop::test::writeText(tmp / "gt.txt", "9 0\n12 3\n");
  const auto outside =
      run("--sequence " + desk + " --gt " + (tmp / "gt.txt") + " --models vlad --out " + (tmp / "o"));
  EXPECT_EQ(outside.code, 1) << outside.out;
  EXPECT_NE(outside.out.find("pair 12 3 is outside the 10 images"), std::string::npos) << outside.out;
  const auto model =
      run("--sequence " + desk + " --gt " + (tmp / "gt.txt") + " --models hbow,sift --out " + (tmp / "o"));
  EXPECT_NE(model.code, 0);
  EXPECT_NE(model.out.find("sift"), std::string::npos) << model.out;
}

// A model trained with other extractor settings than the run's is refused before any image is read, with
// both settings and the way out named; --force-extractor runs it with a warning.
TEST(EvalLoopsTool, RefusesAModelOfOtherExtractorSettingsUnlessForced) {
  const std::string desk = binloop::test::sharedData("tum_desk");
  BINLOOP_REQUIRE_DATA(desk);
  binloop::test::TempDir tmp;
  const auto train = trainVlad(desk, "--features 500", tmp / "vlad.bin");
  ASSERT_EQ(train.code, 0) << train.out;
  EXPECT_NE(train.out.find("from binloop ORB with the Gaussian BRIEF pattern (500 features, scale 1.2, 8 "
                           "levels, FAST 20/7, 30-px cells, full-size images)"),
            std::string::npos)
      << train.out;
  binloop::test::writeText(tmp / "gt.txt", "9 0\n");
  const std::string common = "--sequence " + desk + " --gt " + (tmp / "gt.txt") +
                             " --models vlad --vocab-dir " + tmp.path() + " --window 0 --reference 1 --out " +
                             (tmp / "out");
  const auto refused = run(common);
  EXPECT_EQ(refused.code, 1) << refused.out;
  EXPECT_NE(
      refused.out.find(
          "eval-loops: error: " + (tmp / "vlad.bin") +
          ": trained on descriptors of binloop ORB with the Gaussian BRIEF pattern (500 features, scale "
          "1.2, 8 levels, FAST 20/7, 30-px cells, full-size images), but they will come from binloop ORB "
          "with the Gaussian BRIEF pattern (2000 features, "
          "scale 1.2, 8 levels, FAST 20/7, 30-px cells, full-size images) (differ: features 500 vs "
          "2000); a vocabulary only fits descriptors like those it was trained on: retrain it with "
          "these settings, or use it anyway with --force-extractor"),
      std::string::npos)
      << refused.out;
  EXPECT_EQ(refused.out.find("keyframes"), std::string::npos) << "refused before reading images:\n"
                                                              << refused.out;
  const auto forced = run(common + " --force-extractor");
  EXPECT_EQ(forced.code, 0) << forced.out;
  EXPECT_NE(forced.out.find("eval-loops: warning: " + (tmp / "vlad.bin") +
                            ": trained on descriptors of binloop ORB with the Gaussian BRIEF pattern (500"),
            std::string::npos)
      << forced.out;
  EXPECT_NE(forced.out.find("used anyway (--force-extractor)"), std::string::npos) << forced.out;
  // The same settings as training: no warning.
  const auto same = run(common + " --features 500");
  EXPECT_EQ(same.code, 0) << same.out;
  EXPECT_EQ(same.out.find("warning"), std::string::npos) << same.out;
}

// A model records the BRIEF tests and the image size it was trained with, and eval-loops queries it the same
// way unless told otherwise: a photo vocabulary (ORB's learned tests, 1024 px) needs no flag. Asked for
// other settings, it refuses and names the difference.
TEST(EvalLoopsTool, QueriesFollowThePatternAndImageSizeTheModelRecords) {
  const std::string desk = binloop::test::sharedData("tum_desk");
  BINLOOP_REQUIRE_DATA(desk);
  binloop::test::TempDir tmp;
  const auto learned = trainVlad(desk, "--pattern orb", tmp / "l/vlad.bin");
  ASSERT_EQ(learned.code, 0) << learned.out;
  const auto small = trainVlad(desk, "--max-side 320", tmp / "s/vlad.bin");
  ASSERT_EQ(small.code, 0) << small.out;
  binloop::test::writeText(tmp / "gt.txt", "9 0\n");
  const std::string common = "--sequence " + desk + " --gt " + (tmp / "gt.txt") +
                             " --models vlad --window 0 --reference 1 --out " + (tmp / "out") +
                             " --vocab-dir ";
  const auto follows = run(common + (tmp / "l"));
  EXPECT_EQ(follows.code, 0) << follows.out;
  EXPECT_NE(follows.out.find("was trained on descriptors with orb BRIEF tests; queries use them too"),
            std::string::npos)
      << follows.out;
  const auto refused = run(common + (tmp / "l") + " --pattern gaussian");
  EXPECT_EQ(refused.code, 1) << refused.out;
  EXPECT_NE(
      refused.out.find("(differ: extractor binloop ORB with ORB's learned pattern vs binloop ORB with the "
                       "Gaussian BRIEF pattern)"),
      std::string::npos)
      << refused.out;
  const auto scaled = run(common + (tmp / "s"));
  EXPECT_EQ(scaled.code, 0) << scaled.out;
  EXPECT_NE(scaled.out.find(
                "was trained on images scaled to a longer side <= 320 px; queries are scaled the same way"),
            std::string::npos)
      << scaled.out;
  const auto full = run(common + (tmp / "s") + " --max-side 0");
  EXPECT_EQ(full.code, 1) << full.out;
  EXPECT_NE(full.out.find("max side 320 vs none"), std::string::npos) << full.out;
}

// --near-miss scores each model a second time with proposals close to their query that the ground truth does
// not list dropped, as <model>~near: with a radius beyond every proposal only right ones are left. It needs
// poses and says so.
TEST(EvalLoopsTool, NearMissesCountNeitherRightNorWrong) {
  const std::string seq = binloop::test::sharedData("kitti/real_06_000_050");
  BINLOOP_REQUIRE_DATA(seq + "/poses.txt");
  const std::string vocab = std::string(BINLOOP_ROOT_DIR) + "/vocab/photos";
  BINLOOP_REQUIRE_DATA(vocab + "/vlad.bin");
  binloop::test::TempDir tmp;
  const auto r =
      run("--sequence " + seq + " --models vlad --vocab-dir " + vocab +
          " --window 2 --reference 1 --gt-radius 4 --near-miss 1000 --consistency 2 --out " + (tmp / "out"));
  ASSERT_EQ(r.code, 0) << r.out;
  std::map<std::string, std::vector<double>> rows;  // model -> r_at_100p, ..., precision_at_bar (column 9)
  for (const auto& cells : csvRows(tmp / "out/summary.csv")) {
    for (size_t c = 1; c < cells.size(); ++c)
      rows[cells[0]].push_back(cells[c].empty() ? -1 : std::atof(cells[c].c_str()));
  }
  ASSERT_EQ(rows.count("vlad"), 1u) << r.out;
  ASSERT_EQ(rows.count("vlad~near"), 1u) << r.out;
  ASSERT_EQ(rows.count("vlad+c2~near"), 1u) << "the consistency row gets its near-miss twin too:\n" << r.out;
  EXPECT_DOUBLE_EQ(rows["vlad+c2~near"][7], 1.0) << "a wrong proposal was left:\n" << r.out;
  // Only right proposals left: R@100P is the share of findable queries whose proposal is right.
  int right = 0, wrong = 0;
  for (const auto& cells : csvRows(tmp / "out/queries_vlad.csv"))
    if (cells.size() > 4 && !cells[2].empty() && cells[0] != "query") (cells[4] == "1" ? right : wrong)++;
  EXPECT_GT(wrong, 0) << "nothing to drop: the check below cannot fail";
  EXPECT_NEAR(rows["vlad~near"][0], right / rows["vlad"][13], 1e-6) << r.out;
  EXPECT_DOUBLE_EQ(rows["vlad~near"][7], 1.0) << "a wrong proposal was left:\n" << r.out;
  const std::string desk = binloop::test::sharedData("tum_desk");
  binloop::test::writeText(tmp / "gt.txt", "9 0\n");
  const auto no_poses =
      run("--sequence " + desk + " --gt " + (tmp / "gt.txt") + " --near-miss 5 --out " + (tmp / "o"));
  EXPECT_EQ(no_poses.code, 2) << no_poses.out;
  EXPECT_NE(no_poses.out.find("--near-miss needs a pose for every image"), std::string::npos) << no_poses.out;
}
