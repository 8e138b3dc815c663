// eval-loops: runs loop models over the same images and measures them against ground-truth loop pairs
// (see docs/loop_models.md, "Evaluating loop detection").
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <set>
#include <sstream>

#include "binloop/eval/loop_ground_truth.h"
#include "binloop/eval/loop_metrics.h"
#include "binloop/eval/pr_plot.h"
#include "binloop/eval/temporal_consistency.h"
#include "binloop/features/extract_options_cli.h"
#include "binloop/features/image_features.h"
#include "binloop/io/data_error.h"
#include "binloop/io/filesystem.h"
#include "binloop/io/trajectory_io.h"
#include "binloop/place/place_recognizer.h"
#include "binloop/util/cli_args.h"
#include "binloop/util/package_paths.h"
#include "binloop/util/percentile.h"
#include "binloop/util/progress_bar.h"

namespace fs = std::filesystem;
using namespace binloop;

namespace {

struct ModelRun {
  std::string name;
  LoopMetrics metrics;
  std::vector<LoopPrediction> predictions;
  std::vector<double> signature_ms, query_ms;
  size_t bytes_per_kf = 0;
  int same_found = 0, reverse_found = 0, segments_found = 0;
  std::string missed_segments;
};

}  // namespace

int main(int argc, char** argv) {
  CliArgs args("eval-loops",
               "eval-loops --sequence <dir> --gt <pairs.txt> --vocab-dir <dir> --out <dir> [options]");
  args.option("sequence",
              "KITTI-layout sequence (image_0/ is used) or a folder of png/jpg images in natural order")
      .option(
          "gt",
          "ground-truth loop pairs, 'query ref' frame indices per line, # comments (default: from the poses)")
      .option("gt-radius", "without --gt: frames within this many metres (poses) are loops", "6")
      .option("models", "comma-separated models, or all", "all")
      .option("vocab-dir", "folder holding <model>.bin for each model; default: the package's",
              packagePath(kShippedModelDir))
      .option("out", "folder for the results")
      .option("step", "keyframe every step-th frame", "1")
      .option("window", "frames before a query that are never candidates (temporal neighbours)", "300")
      .option("reference", "previous keyframes that set each query's bar (the covisible neighbours of SLAM)",
              "3")
      .option("poses", "poses for same/reverse direction (default: <sequence>/poses.txt when present)")
      .option("consistency",
              "also score each model behind ORB-SLAM2's consistency check over this many consecutive "
              "keyframes (0 = off)",
              "3")
      .option("near-miss",
              "with poses: also score each model with proposals this close to their query (metres) that are "
              "not ground-truth loops counted neither right nor wrong, as <model>~near and <model>+cN~near "
              "(0 = off)",
              "0")
      .option("segment-gap", "frames between ground-truth queries that start a new revisit segment", "50")
      .option("fabmap-l2-offset",
              "offset added to the closest reference's L2 distance in fabmap's pre-filter", "0.05")
      .option("hbow-min-bar", "hbow's bar never goes below this L1 score", "0.005")
      .option("vladpq-slack",
              "vladpq's pre-filter passes keyframes sharing this many (word, code) pairs fewer than the best "
              "reference",
              "8")
      .option("vlad-reference-rank",
              "vlad's and hmvlad's bar is the distance to this closest reference (1: the closest; beyond "
              "--reference: the farthest)",
              "3")
      .option("rank-floor", "ranking: an L1-score bar (hbow) counts as at least this", "0.03")
      .option("rank-cap",
              "ranking: a distance bar (vlad, hmvlad, vladpq) counts as at most this fraction of the bits",
              "0.35")
      .option("dump-ranked",
              "also write ranked_<model>.csv: each query's bar and its N best keyframes by raw score", "0")
      .flag("force-extractor",
            "use a model trained with other extractor settings than these (warns instead of refusing)");
  declareExtractOptions(args);
  return runTool("eval-loops", [&] {
    if (!args.parse(argc, argv)) return 0;
    for (const char* o : {"sequence", "out"})
      if (!args.has(o)) throw CliError(std::string("--") + o + " is required");
    const int step = static_cast<int>(args.integer("step")),
              window = static_cast<int>(args.integer("window"));
    const int nref = static_cast<int>(args.integer("reference"));
    const int consistency = static_cast<int>(args.integer("consistency"));
    const double near_miss = args.number("near-miss");
    if (step < 1 || window < 0 || nref < 1 || consistency < 0 || near_miss < 0)
      throw CliError("--step and --reference must be >= 1, --window, --consistency and --near-miss >= 0");
    std::vector<std::string> models;
    if (args.str("models") == "all") {
      models = placeModelNames();
    } else {
      std::stringstream ss(args.str("models"));
      for (std::string m; std::getline(ss, m, ',');) models.push_back(m);
    }
    for (const auto& m : models) modelTypeFromName(m);  // unknown names fail before any work
    ExtractOptions eo = extractOptionsFrom(args);
    const auto modelFile = [&](const std::string& name) {
      return (fs::path(args.str("vocab-dir")) / (name + ".bin")).string();
    };
    // A model records the BRIEF tests and the image size it was trained with; without --pattern and
    // --max-side the queries follow the first model, so a photo vocabulary (ORB's learned tests, 1024 px)
    // takes images of any size with no flag. Every other model is then checked against the same settings.
    ModelHeader first;
    try {
      first = readModelHeader(modelFile(models.front()));
    } catch (const PlaceError&) {  // a missing or broken file is reported where the model is loaded
    }
    const bool binloop_orb = first.extractor.kind == ExtractorKind::kBinloopOrb ||
                             first.extractor.kind == ExtractorKind::kBinloopOrbRbrief;
    if (binloop_orb && !args.has("pattern")) {
      eo.orb.pattern = first.extractor.kind == ExtractorKind::kBinloopOrbRbrief
                           ? BriefPatternKind::kOrbLearned
                           : BriefPatternKind::kGaussian;
      if (eo.orb.pattern != OrbSlamParams{}.pattern)
        std::cout << "eval-loops: " << modelFile(models.front()) << " was trained on descriptors with "
                  << briefPatternName(eo.orb.pattern)
                  << " BRIEF tests; queries use them too (--pattern to choose)\n";
    }
    if (binloop_orb && !args.has("max-side") && first.extractor.max_side > 0) {
      eo.max_side = static_cast<int>(first.extractor.max_side);
      std::cout << "eval-loops: " << modelFile(models.front())
                << " was trained on images scaled to a longer side <= " << eo.max_side
                << " px; queries are scaled the same way (--max-side 0: full size)\n";
    }
    // Every model file must have been trained on descriptors of these settings (or --force-extractor):
    // checked from the headers alone, below.
    ExtractorCheck extractor_check;
    extractor_check.expected = extractorSettings(eo);
    extractor_check.force = args.has("force-extractor");
    extractor_check.warn = [](const std::string& line) {
      std::cerr << "eval-loops: warning: " << line << "\n";
    };
    const auto images = listImages(args.str("sequence"));
    std::vector<Pose3> poses;
    const std::string poses_path =
        args.has("poses") ? args.str("poses") : (fs::path(args.str("sequence")) / "poses.txt").string();
    if (fs::exists(poses_path)) poses = readKittiPoses(poses_path);
    std::vector<std::pair<int, int>> pairs;
    if (args.has("gt")) {
      pairs = readIndexPairs(args.str("gt"));
    } else if (poses.size() == images.size()) {
      pairs = loopPairsFromPoses(poses, args.number("gt-radius"), window);
      std::cout << "ground truth: frames within " << args.number("gt-radius") << " m of each other in "
                << poses_path << "\n";
    } else {
      throw CliError("--gt is required when there are no poses for every image (" + poses_path + ")");
    }
    if (near_miss > 0 && poses.size() != images.size())
      throw CliError("--near-miss needs a pose for every image (" + poses_path + ")");
    fs::create_directories(args.str("out"));

    // Keyframes and the ground truth that can be found among them.
    std::vector<int> kf_frames;
    for (int f = 0; f < static_cast<int>(images.size()); f += step) kf_frames.push_back(f);
    std::set<int> kf_set(kf_frames.begin(), kf_frames.end());
    std::set<std::pair<int, int>> truth;
    std::set<int> positives, same_dir, reverse_dir;
    for (const auto& [q, r] : pairs) {
      if (q < 0 || r < 0 || q >= static_cast<int>(images.size()) || r >= static_cast<int>(images.size()))
        throw DataError((args.has("gt") ? args.str("gt") : poses_path) + ": pair " + std::to_string(q) + " " +
                        std::to_string(r) + " is outside the " + std::to_string(images.size()) + " images");
      truth.insert({q, r});
      if (!kf_set.count(q) || !kf_set.count(r) || r > q - window || r >= q) continue;
      positives.insert(q);
      if (poses.size() == images.size()) {
        const bool reverse = poses[q].linear().col(2).dot(poses[r].linear().col(2)) < 0;
        (reverse ? reverse_dir : same_dir).insert(q);
      }
    }
    for (int q : reverse_dir) same_dir.erase(q);  // a query with both kinds counts as a reverse revisit
    std::vector<std::set<int>> segments;
    for (int q : positives) {
      if (segments.empty() || q - *segments.back().rbegin() > args.integer("segment-gap"))
        segments.emplace_back();
      segments.back().insert(q);
    }

    // After the arguments and the ground truth (their errors say more), before any image is decoded.
    for (const auto& m : models) checkModelExtractor(modelFile(m), extractor_check);
    std::vector<std::string> kf_paths;
    for (int f : kf_frames) kf_paths.push_back(images[f]);
    std::vector<Descriptors> desc;
    {
      ProgressBar bar("ORB features", kf_paths.size());
      desc = extractDescriptors(kf_paths, eo, [&](size_t d, size_t n) { bar.update(d, n); });
    }
    std::cout << images.size() << " images, " << kf_frames.size() << " keyframes (step " << step << "), "
              << positives.size() << " keyframes with a findable loop in " << segments.size() << " segments ("
              << same_dir.size() << " same direction, " << reverse_dir.size() << " reverse)\n";

    std::vector<ModelRun> runs;
    // Metrics of one run's predictions, its missed segments, and its PR curve file.
    // A proposal just beyond the ground truth's radius is a near miss, not a wrong place: the ~near rows
    // count it neither right nor wrong, so that one near miss does not set the bar for a whole route.
    std::set<std::pair<int, int>> near_pairs;
    if (near_miss > 0)
      for (const auto& pair : loopPairsFromPoses(poses, near_miss, 0)) near_pairs.insert(pair);
    auto score = [&](ModelRun& run, const std::set<std::pair<int, int>>& ignored) {
      run.metrics = evaluateLoops(run.predictions, truth, positives, ignored);
      run.segments_found = 0;
      run.missed_segments.clear();
      const double t = run.metrics.threshold_100p;
      const int tier = run.metrics.tier_100p;
      run.same_found = foundAt(run.predictions, truth, same_dir, t, tier);
      run.reverse_found = foundAt(run.predictions, truth, reverse_dir, t, tier);
      for (const auto& seg : segments) {
        if (foundAt(run.predictions, truth, seg, t, tier) > 0) {
          run.segments_found++;
        } else {
          run.missed_segments += (run.missed_segments.empty() ? "" : " ") + std::to_string(*seg.begin()) +
                                 "-" + std::to_string(*seg.rbegin());
        }
      }
      std::ofstream pr(fs::path(args.str("out")) / ("pr_" + run.name + ".csv"));
      pr << "tier,threshold,precision,recall\n";
      for (const auto& pt : run.metrics.curve)
        pr << pt.tier << "," << pt.threshold << "," << pt.precision << "," << pt.recall << "\n";
    };
    for (const auto& name : models) {
      RecognizerOptions ro;
      ro.model_file = modelFile(name);
      ro.extractor = extractor_check;
      ro.extractor.warn = [](const std::string&) {};  // warned once above
      ro.fabmap_l2_offset = args.number("fabmap-l2-offset");
      ro.hbow_min_bar = args.number("hbow-min-bar");
      ro.vladpq_shared_slack = static_cast<int>(args.integer("vladpq-slack"));
      ro.vlad_reference_rank = static_cast<int>(args.integer("vlad-reference-rank"));
      ro.ranking.score_floor = args.number("rank-floor");
      ro.ranking.distance_cap = args.number("rank-cap");
      auto rec = makePlaceRecognizer(name, ro);
      rec->setKeepDescriptors(false);
      ModelRun run;
      run.name = name;
      std::ofstream qcsv(fs::path(args.str("out")) / ("queries_" + name + ".csv"));
      qcsv << "query,status,candidate,confidence,correct,signature_ms,query_ms,detail\n";
      std::vector<QueryOffers> offers;
      const auto dump_ranked = static_cast<size_t>(std::max(0L, args.integer("dump-ranked")));
      std::ofstream rcsv;
      if (dump_ranked) {
        rcsv.open(fs::path(args.str("out")) / ("ranked_" + name + ".csv"));
        rcsv << "query,status,threshold,ranked\n";
      }
      ProgressBar bar(name, kf_frames.size());
      for (size_t i = 0; i < kf_frames.size(); ++i) {
        const int f = kf_frames[i];
        LoopPrediction p{f, -1, 0};
        if (desc[i].empty()) {  // a featureless frame cannot be a keyframe of any model
          qcsv << f << ",no_features,,,,,,\n";
          run.predictions.push_back(p);
          offers.push_back({f, {}});
          continue;
        }
        run.signature_ms.push_back(rec->add(static_cast<KeyframeId>(f), desc[i]));
        QueryScope scope;
        for (size_t j = i; j-- > 0 && scope.reference.size() < static_cast<size_t>(nref);)
          scope.reference.push_back(kf_frames[j]);
        for (size_t j = i; j-- > 0 && kf_frames[j] > f - window;) scope.ignore.push_back(kf_frames[j]);
        scope.max_ranked = dump_ranked;
        const QueryResult r = rec->query(static_cast<KeyframeId>(f), scope);
        if (dump_ranked) {
          rcsv << f << "," << statusName(r.status) << "," << r.threshold << ",";
          for (size_t c = 0; c < r.ranked.size(); ++c)
            rcsv << (c ? ";" : "") << r.ranked[c].id << ":" << r.ranked[c].score;
          rcsv << "\n";
        }
        run.query_ms.push_back(r.total_ms);
        if (const Candidate* best = r.best()) {
          p.candidate = static_cast<int>(best->id);
          p.confidence = best->confidence;
          p.passed = !r.candidates.empty();
        }
        run.predictions.push_back(p);
        offers.push_back({f, {}});
        for (const auto& c : r.candidates)
          offers.back().offers.push_back({static_cast<int>(c.id), c.confidence, true});
        if (r.has_best_rejected)
          offers.back().offers.push_back(
              {static_cast<int>(r.best_rejected.id), r.best_rejected.confidence, false});
        std::string detail = r.detail;
        std::replace(detail.begin(), detail.end(), ',', ';');
        qcsv << f << "," << statusName(r.status) << ","
             << (p.candidate >= 0 ? std::to_string(p.candidate) : "") << "," << p.confidence << ","
             << (p.candidate >= 0 && truth.count({f, p.candidate}) ? 1 : 0) << "," << run.signature_ms.back()
             << "," << r.total_ms << "," << detail << "\n";
        bar.update(i + 1);
      }
      bar.finish();
      run.bytes_per_kf = rec->indexBytesPerKeyframe();
      score(run, {});
      const size_t first = runs.size();
      runs.push_back(run);
      if (consistency > 0) {
        // Groups are a keyframe and the two on each side; two groups overlap within 4 keyframes.
        ModelRun c = run;
        c.name = name + "+c" + std::to_string(consistency);
        c.predictions = consistentPredictions(offers, consistency, 4 * step);
        score(c, {});
        runs.push_back(std::move(c));
      }
      if (near_miss > 0) {
        for (size_t i = first, n = runs.size(); i < n; ++i) {
          ModelRun near = runs[i];
          near.name += "~near";
          score(near, near_pairs);
          runs.push_back(std::move(near));
        }
      }
    }

    std::vector<PrSeries> series;
    for (const auto& r : runs) series.push_back({r.name, r.metrics.curve});
    writePrPlot((fs::path(args.str("out")) / "pr.png").string(),
                fs::path(args.str("sequence")).filename().string(), series);
    std::ofstream sum(fs::path(args.str("out")) / "summary.csv");
    sum << "model,r_at_100p,auc,signature_ms_median,query_ms_median,bytes_per_kf,signature_ms_p95,query_ms_"
           "p95,"
           "precision_at_bar,recall_at_bar,same_direction_r_at_100p,reverse_direction_r_at_100p,segments_"
           "found,segments,"
           "positives,keyframes\n";
    std::ostringstream table;
    int name_width = 10;  // "vlad+c3~near" and longer names get their own column
    for (const auto& r : runs) name_width = std::max(name_width, static_cast<int>(r.name.size()) + 1);
    table << std::left << std::setw(name_width) << "model" << std::right << std::setw(8) << "R@100P"
          << std::setw(7) << "AUC" << std::setw(9) << "same" << std::setw(9) << "reverse" << std::setw(10)
          << "segments" << std::setw(10) << "sig ms" << std::setw(9) << "p95" << std::setw(10) << "query ms"
          << std::setw(9) << "p95" << std::setw(10) << "B/kf"
          << "  P/R at bar\n";
    for (const auto& r : runs) {
      const auto& m = r.metrics;
      const double same = same_dir.empty() ? 0 : double(r.same_found) / same_dir.size();
      const double rev = reverse_dir.empty() ? 0 : double(r.reverse_found) / reverse_dir.size();
      sum << r.name << "," << m.r_at_100p << "," << m.auc << "," << percentile(r.signature_ms, 0.5) << ","
          << percentile(r.query_ms, 0.5) << "," << r.bytes_per_kf << "," << percentile(r.signature_ms, 0.95)
          << "," << percentile(r.query_ms, 0.95) << "," << m.precision_at_bar << "," << m.recall_at_bar << ","
          << (same_dir.empty() ? std::string("") : std::to_string(same)) << ","
          << (reverse_dir.empty() ? std::string("") : std::to_string(rev)) << "," << r.segments_found << ","
          << segments.size() << "," << m.positives << "," << kf_frames.size() << "\n";
      char line[256];
      std::snprintf(line, sizeof line, "%-*s%8.3f%7.3f%9s%9s%10s%10.3f%9.3f%10.4f%9.4f%10zu  %.2f/%.2f\n",
                    name_width, r.name.c_str(), m.r_at_100p, m.auc,
                    same_dir.empty() ? "-" : std::to_string(same).substr(0, 5).c_str(),
                    reverse_dir.empty() ? "-" : std::to_string(rev).substr(0, 5).c_str(),
                    (std::to_string(r.segments_found) + "/" + std::to_string(segments.size())).c_str(),
                    percentile(r.signature_ms, 0.5), percentile(r.signature_ms, 0.95),
                    percentile(r.query_ms, 0.5), percentile(r.query_ms, 0.95), r.bytes_per_kf,
                    m.precision_at_bar, m.recall_at_bar);
      table << line;
      if (!r.missed_segments.empty())
        table << "            missed at 100 % precision: segments " << r.missed_segments << "\n";
    }
    std::cout << table.str() << "results in " << args.str("out")
              << " (summary.csv, pr.png, pr_<model>.csv, queries_<model>.csv)\n";
    return 0;
  });
}
