// learn-pattern: learns the extractor's 256 BRIEF tests from training images, as ORB learned rBRIEF, and
// writes them as the C++ table src/core/features/brief_pattern.inc (see features/brief_pattern_learning.h).
#include <atomic>
#include <exception>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <mutex>
#include <sstream>
#include <thread>

#include "binloop/features/brief_pattern_learning.h"
#include "binloop/features/extract_options_cli.h"
#include "binloop/io/data_error.h"
#include "binloop/io/kitti_sequence.h"
#include "binloop/util/cli_args.h"
#include "binloop/util/hash_random.h"
#include "binloop/util/progress_bar.h"

#include <opencv2/imgproc.hpp>

int main(int argc, char** argv) {
  binloop::CliArgs args("learn-pattern",
                        "learn-pattern --images <dir>... --out <brief_pattern.inc> [options]");
  args.option("images", "folder of images or KITTI-layout sequence (image_0/ is used); repeat for more")
      .option("every", "use every n-th image of each folder", "1")
      .option("out", "C++ table to write")
      .option("keypoints", "oriented keypoints to learn from, spread evenly over the images", "200000")
      .option("min-separation", "a test's two points differ by at least this in x or y (pixels)", "5")
      .option("start-threshold", "first |correlation| bound of the greedy selection", "0.1")
      .option("threshold-step", "raise of the bound when fewer than 256 tests survive", "0.01")
      .option("pool", "best-balanced candidates the greedy selection looks at", "12000")
      .option("tie-margin", "grey levels within which a test's two values are a near-tie", "5")
      .option("max-tie-share",
              "leave out tests that are near-ties on more than this share of keypoints (1: off)", "1")
      .option("seed", "keypoint sampling seed", "1")
      .option("data-note", "what the images are, for the table's header", "")
      .flag("skip-unreadable", "skip images that cannot be read as 8-bit instead of stopping");
  binloop::declareExtractOptions(args);
  return binloop::runTool("learn-pattern", [&] {
    if (!args.parse(argc, argv)) return 0;
    if (!args.has("out") || !args.has("images")) throw binloop::CliError("--images and --out are required");
    if (args.has("pattern"))
      throw binloop::CliError(
          "--pattern does not apply: learn-pattern learns its own tests from the keypoints");
    binloop::ExtractOptions eo = binloop::extractOptionsFrom(args);
    eo.orb.pattern = binloop::BriefPatternKind::kGaussian;  // the keypoints and angles; the tests are learned
    const long every = args.integer("every"), keypoints = args.integer("keypoints");
    if (every < 1 || keypoints < 1) throw binloop::CliError("--every and --keypoints must be >= 1");
    std::vector<std::string> paths;
    for (const auto& dir : args.all("images")) {
      const auto files = binloop::listImages(dir);
      for (size_t i = 0; i < files.size(); i += every) paths.push_back(files[i]);
    }
    const uint64_t seed = static_cast<uint64_t>(args.integer("seed"));
    const size_t per_image = (static_cast<size_t>(keypoints) + paths.size() - 1) / paths.size();
    const binloop::OrbSlamExtractor extractor(eo.orb);
    std::vector<binloop::PatchSamples> per(paths.size());
    std::vector<std::string> skipped(paths.size());
    {
      binloop::ProgressBar bar("oriented patches", paths.size());
      std::atomic<size_t> next{0}, done{0};
      std::mutex m;
      std::exception_ptr error;
      auto work = [&] {
        for (size_t i; (i = next++) < paths.size();) {
          try {
            cv::Mat img = binloop::readGrayImage(paths[i]);
            const int side = std::max(img.cols, img.rows);
            if (eo.max_side > 0 && side > eo.max_side) {
              const double s = double(eo.max_side) / side;
              cv::resize(img, img, cv::Size(), s, s, cv::INTER_AREA);
            }
            per[i] = binloop::samplePatches(img, extractor, per_image, binloop::hashCombine(seed, i));
          } catch (const binloop::DataError& e) {
            skipped[i] = e.what();
            if (!args.has("skip-unreadable")) {
              std::lock_guard<std::mutex> l(m);
              if (!error) error = std::current_exception();
              next = paths.size();
            }
          } catch (...) {
            std::lock_guard<std::mutex> l(m);
            if (!error) error = std::current_exception();
            next = paths.size();
          }
          std::lock_guard<std::mutex> l(m);
          bar.update(++done);
        }
      };
      std::vector<std::thread> pool;
      for (int t = 1; t < std::max(1, eo.threads); ++t) pool.emplace_back(work);
      work();
      for (auto& t : pool) t.join();
      if (error) std::rethrow_exception(error);
    }
    binloop::PatchSamples all;
    size_t used = 0;
    for (size_t i = 0; i < paths.size(); ++i) {
      if (!skipped[i].empty()) std::cerr << "learn-pattern: skipped " << skipped[i] << "\n";
      used += per[i].keypoints() > 0;
      all.append(per[i]);
      per[i] = {};
    }
    binloop::PatternLearningOptions lo;
    lo.min_separation = static_cast<int>(args.integer("min-separation"));
    lo.start_threshold = args.number("start-threshold");
    lo.threshold_step = args.number("threshold-step");
    lo.pool = static_cast<size_t>(args.integer("pool"));
    lo.tie_margin = static_cast<int>(args.integer("tie-margin"));
    lo.max_tie_share = args.number("max-tie-share");
    lo.threads = eo.threads;
    std::cout << "learn-pattern: " << all.keypoints() << " oriented keypoints from " << used << " images"
              << std::endl;
    const binloop::LearnedPattern lp = binloop::learnBriefPattern(all, lo);
    double bias = 0;
    for (double m : lp.mean) bias += std::abs(m - 0.5);
    bias /= lp.mean.size();
    std::ostringstream summary;
    summary << std::fixed << std::setprecision(3) << lp.candidates
            << " candidate tests; 256 kept at |correlation| < " << lp.threshold << " after walking the "
            << lp.walked << " best-balanced; on the training keypoints: mean |P(bit) - 0.5| " << bias
            << ", mean |correlation| " << lp.mean_abs_correlation << ", max " << lp.max_abs_correlation
            << ", near-ties (|dI| <= " << lo.tie_margin << ") " << lp.tie_share;
    std::cout << "learn-pattern: " << summary.str() << std::endl;

    std::ofstream out(args.str("out"));
    if (!out) throw binloop::CliError("cannot write " + args.str("out"));
    std::string command = "learn-pattern";
    for (int i = 1; i < argc; ++i) command += std::string(" ") + argv[i];
    out << "// GENERATED by binloop's `learn-pattern` (src/tools/learn_pattern.cpp); do not edit. The "
           "extractor's 256\n"
           "// BRIEF tests {ax, ay, bx, by}: bit = I(a) < I(b) on the smoothed level, both points rotated by "
           "the\n"
           "// keypoint angle (features/orb_slam_extractor.h), learned as ORB learned rBRIEF (Rublee et al. "
           "2011, 4.3;\n"
           "// features/brief_pattern_learning.h).\n"
           "// Command: "
        << command << "\n// Data: " << used << " images (" << all.keypoints() << " oriented keypoints, seed "
        << seed << "), extractor " << binloop::extractorSettings(eo).describe() << ".\n";
    if (!args.str("data-note").empty()) out << "// " << args.str("data-note") << "\n";
    out << "// " << summary.str() << ".\n";
    for (size_t b = 0; b < lp.tests.size(); ++b) {
      const auto& t = lp.tests[b];
      out << "    {" << int(t.ax) << ", " << int(t.ay) << ", " << int(t.bx) << ", " << int(t.by) << "},  // "
          << b << ": P(1) " << std::fixed << std::setprecision(3) << lp.mean[b] << "\n";
    }
    if (!out) throw binloop::CliError("writing " + args.str("out") + " failed");
    std::cout << "learn-pattern: wrote " << args.str("out") << std::endl;
    return 0;
  });
}
