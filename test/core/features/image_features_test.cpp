// Batch extraction for `train` and `eval-loops`: the SLAM's extractor with the SLAM's settings, so that a
// vocabulary sees at run time the descriptors it was trained on.
#include "binloop/features/image_features.h"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "binloop/features/extract_options_cli.h"
#include "binloop/io/kitti_sequence.h"
#include "binloop/pipeline/slam_config.h"
#include "binloop/util/hash_random.h"
#include "support/test_support.h"

using namespace binloop;

namespace {

// Blobs of random grey on a mid-grey ground: corners everywhere.
cv::Mat texturedImage(int w, int h, uint64_t seed) {
  cv::Mat img(h, w, CV_8UC1, cv::Scalar(128));
  HashRng rng(seed);
  for (int i = 0; i < w * h / 400; ++i) {
    const int x = static_cast<int>(rng.below(static_cast<uint64_t>(w))),
              y = static_cast<int>(rng.below(static_cast<uint64_t>(h)));
    cv::rectangle(img, {x, y},
                  {x + 4 + static_cast<int>(rng.below(20)), y + 4 + static_cast<int>(rng.below(20))},
                  cv::Scalar(static_cast<double>(rng.below(256))), -1);
  }
  return img;
}

bool sameDescriptors(const Descriptors& a, const Descriptors& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i)
    if (hamming(a[i], b[i]) != 0) return false;
  return true;
}

ExtractOptions parse(std::vector<std::string> argv) {
  argv.insert(argv.begin(), "tool");
  std::vector<char*> p;
  for (auto& a : argv) p.push_back(a.data());
  CliArgs args("tool", "tool [options]");
  declareExtractOptions(args);
  args.parse(static_cast<int>(p.size()), p.data());
  return extractOptionsFrom(args);
}

}  // namespace

TEST(ImageFeatures, DefaultsAreTheSlamExtractorOfConfigKitti) {
  const ExtractOptions d;
  const SlamConfig c = loadSlamConfig(std::string(BINLOOP_ROOT_DIR) + "/config/kitti.yaml");
  EXPECT_TRUE(d.orb == c.tracker.orb)
      << "config/kitti.yaml's orb: section differs from the defaults of train and eval-loops; the shipped "
         "vocabularies are trained with those defaults (vocab/make_vocab.sh): retrain them, or keep both "
         "equal";
  EXPECT_EQ(d.max_side, 0) << "the SLAM extracts from full-size images";
  EXPECT_EQ(extractorSettings(d), extractorSettings(c.tracker.orb));
  // The command line's defaults are the same.
  const ExtractOptions cli = parse({});
  EXPECT_TRUE(cli.orb == d.orb);
  EXPECT_EQ(cli.max_side, 0);
}

TEST(ImageFeatures, ExtractsWithTheSlamExtractor) {
  test::TempDir dir;
  cv::imwrite(dir / "a.png", texturedImage(640, 360, 1));
  cv::imwrite(dir / "big.png", texturedImage(1600, 500, 2));
  ExtractOptions o;
  o.orb.features = 800;
  const OrbSlamExtractor ex(o.orb);
  auto got = extractDescriptors({dir / "a.png", dir / "big.png"}, o);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_GT(got[0].size(), 700u);
  EXPECT_TRUE(sameDescriptors(got[0], ex.extract(readGrayImage(dir / "a.png")).descriptors));
  EXPECT_TRUE(sameDescriptors(got[1], ex.extract(readGrayImage(dir / "big.png")).descriptors));
  // max_side scales larger images down (area interpolation) before extracting; smaller ones are untouched.
  o.max_side = 800;
  got = extractDescriptors({dir / "a.png", dir / "big.png"}, o);
  cv::Mat small;
  cv::resize(readGrayImage(dir / "big.png"), small, cv::Size(), 0.5, 0.5, cv::INTER_AREA);
  EXPECT_TRUE(sameDescriptors(got[0], ex.extract(readGrayImage(dir / "a.png")).descriptors));
  EXPECT_TRUE(sameDescriptors(got[1], ex.extract(small).descriptors));
  // Threads do not change the result or its order.
  std::vector<std::string> paths;
  for (int i = 0; i < 5; ++i) {
    paths.push_back(dir / ("s" + std::to_string(i) + ".png"));
    cv::imwrite(paths.back(), texturedImage(300 + 40 * i, 200, 10 + static_cast<uint64_t>(i)));
  }
  o.threads = 1;
  const auto one = extractDescriptors(paths, o);
  o.threads = 3;
  const auto three = extractDescriptors(paths, o);
  for (size_t i = 0; i < paths.size(); ++i) EXPECT_TRUE(sameDescriptors(one[i], three[i])) << i;
}

TEST(ImageFeatures, CommandLineSetsEveryExtractorSetting) {
  const ExtractOptions o =
      parse({"--features", "1000", "--scale-factor", "1.3", "--pyramid-levels", "6", "--ini-fast", "25",
             "--min-fast", "9", "--cell-px", "40", "--max-side", "1024", "--threads", "1"});
  EXPECT_EQ(o.orb.features, 1000);
  EXPECT_EQ(o.orb.scale_factor, 1.3f);
  EXPECT_EQ(o.orb.levels, 6);
  EXPECT_EQ(o.orb.ini_fast, 25);
  EXPECT_EQ(o.orb.min_fast, 9);
  EXPECT_EQ(o.orb.cell_px, 40);
  EXPECT_EQ(o.max_side, 1024);
  EXPECT_EQ(o.threads, 1);
  EXPECT_EQ(extractorSettings(o).describe(),
            "binloop ORB with the Gaussian BRIEF pattern (1000 features, scale 1.3, 6 levels, FAST 25/9, "
            "40-px cells, images scaled to a longer "
            "side <= 1024 px)");
  EXPECT_THROW_WITH(
      parse({"--min-fast", "30"}), CliError,
      "extractor options: ORB-SLAM extractor: FAST thresholds need 1 <= min_fast <= ini_fast, got 30 and 20");
  EXPECT_THROW_WITH(parse({"--max-side", "-1"}), CliError, "--max-side must be >= 0");
  EXPECT_THROW_WITH(parse({"--grid-cell", "64"}), CliError, "--grid-cell is retired");
  EXPECT_EQ(parse({}).orb.pattern, BriefPatternKind::kGaussian);
  EXPECT_EQ(parse({"--pattern", "orb"}).orb.pattern, BriefPatternKind::kOrbLearned);
  EXPECT_EQ(extractorSettings(parse({"--pattern", "orb"})).kind, ExtractorKind::kBinloopOrbRbrief);
  EXPECT_THROW_WITH(parse({"--pattern", "brisk"}), CliError,
                    "--pattern: unknown BRIEF pattern 'brisk' (known: orb, gaussian)");
}

// The shipped vocabularies (vocab/make_vocab.sh) were trained on what the SLAM and the tools extract by
// default: kitti08 with exactly the defaults, photos with the defaults on images scaled to 1024 px and ORB's
// learned BRIEF tests (which eval-loops then follows).
TEST(ImageFeatures, ShippedVocabulariesRecordTheExtractorMakeVocabUsed) {
  const std::string root = std::string(BINLOOP_ROOT_DIR) + "/vocab/";
  ExtractOptions photos;
  photos.max_side = 1024;
  photos.orb.pattern = BriefPatternKind::kOrbLearned;
  int checked = 0;
  for (const char* m : {"hbow", "hbow_k8l5", "fabmap", "vlad", "hmvlad", "vladpq"}) {
    for (const auto& [dir, expected] :
         {std::pair{std::string("kitti08/"), extractorSettings(ExtractOptions{})},
          std::pair{std::string("photos/"), extractorSettings(photos)}}) {
      const std::string f = root + dir + m + ".bin";
      if (!test::exists(f)) continue;  // hbow files are made by vocab/make_vocab.sh, not tracked
      EXPECT_EQ(readModelHeader(f).extractor, expected)
          << f << ": " << readModelHeader(f).extractor.describe();
      ++checked;
    }
  }
  EXPECT_GE(checked, 10);
}
