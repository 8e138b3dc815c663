// Place-recognition benchmark (docs/loop_models.md): hbow transform of 2000 descriptors with a k=10, L=6
// vocabulary; loading a 1M-word vocabulary; one query against 1500 keyframes of 2000 features (ORB-SLAM2's
// keyframes on KITTI) for every model; index memory per keyframe. Medians of 9 runs on this machine; prints
// tables, never pass/fail, and writes the headline numbers to $BINLOOP_BENCH_JSON (scripts/bench.sh sets
// .build/bench/place.json) so that runs can be compared.
//
// Keyframes are real ORB descriptors (2000 per image of the TUM desk and KITTI sample images in ../shared)
// with bit noise, 21 bases repeated over 1500 keyframes: every keyframe resembles ~70 others, a
// pessimistic case for inverted indices. Models come from vocab/kitti08 (the shipped vocabularies).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/core/utility.hpp>
#include <thread>

#include "bench_record.h"
#include "bench_stats.h"
#include "binloop/features/image_features.h"
#include "binloop/place/hbow_recognizer.h"
#include "binloop/place/model_training.h"
#include "binloop/place/place_recognizer.h"
#include "binloop/util/hash_random.h"

using namespace binloop;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

using binloop::bench::median;

Desc256 randomDesc(HashRng& rng) {
  Desc256 d;
  for (auto& w : d.w) w = rng.next();
  return d;
}

// A complete k-ary tree of random descriptors: k + k^2 + ... + k^L nodes, k^L words.
VocabularyTree fullTree(int k, int levels) {
  HashRng rng(1);
  std::vector<VocabularyTree::InputNode> nodes{{0, Desc256{}, false, 0}};
  std::vector<uint32_t> frontier{0};
  for (int l = 0; l < levels; ++l) {
    std::vector<uint32_t> next;
    for (uint32_t p : frontier)
      for (int c = 0; c < k; ++c) {
        next.push_back(static_cast<uint32_t>(nodes.size()));
        nodes.push_back({p, randomDesc(rng), l == levels - 1, static_cast<float>(rng.uniform(0.5, 5))});
      }
    frontier = std::move(next);
  }
  return VocabularyTree::fromNodes(k, levels, Weighting::kTfIdf, nodes);
}

// Headline numbers for the JSON file, by key.
std::map<std::string, double> g_results;

std::vector<Descriptors> keyframes(int n) {
  std::vector<std::string> paths;
  for (const char* d : {"../shared/data/tum_desk", "../shared/data/kitti/sample_00"})
    if (fs::exists(d))
      for (const auto& p : listImages(d)) paths.push_back(p);
  std::vector<Descriptors> base;
  if (!paths.empty()) {
    ExtractOptions eo;
    eo.orb.features = 2000;
    base = extractDescriptors(paths, eo);
  } else {
    std::printf("(../shared/data not found: keyframes are random descriptors)\n");
    HashRng rng(3);
    for (int i = 0; i < 21; ++i) {
      base.emplace_back(2000);
      for (auto& d : base.back()) d = randomDesc(rng);
    }
  }
  std::vector<Descriptors> out;
  for (int i = 0; i < n; ++i) {
    HashRng rng(hashCombine(7, i));
    Descriptors kf;
    for (auto d : base[i % base.size()]) {
      if (!rng.chance(0.8)) continue;
      for (int f = 0; f < 8; ++f) {
        const int b = rng.below(256);
        d.w[b >> 6] ^= uint64_t{1} << (b & 63);
      }
      kf.push_back(d);
    }
    out.push_back(std::move(kf));
  }
  return out;
}

// Medians over this many runs; the machine is a shared VM, so single runs swing by 30 %.
constexpr int kRuns = 9;

void vocabularyBench() {
  const int runs = kRuns;
  std::printf("building a k=10 L=6 vocabulary (1 000 000 words)...\n");
  const VocabularyTree big = fullTree(10, 6);
  const std::string file = (fs::temp_directory_path() / "binloop_bench_1M.bin").string();
  saveHbowModel(big, {}, file);

  std::vector<double> load_ms, transform_ms;
  HashRng rng(5);
  Descriptors d2000(2000);
  for (auto& d : d2000) d = randomDesc(rng);
  for (int r = 0; r < runs; ++r) {
    auto t = Clock::now();
    const auto loaded = HbowRecognizer::loadVocabulary(file);
    load_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t).count());
    BowVector bow;
    t = Clock::now();
    for (int i = 0; i < 50; ++i) loaded->transform(d2000, &bow);  // the mapped tree, as a user gets it
    transform_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t).count() / 50);
  }
  std::printf(
      "\n| hbow vocabulary (k=10, L=6, %zu words, %.1f MB file) | median | min | max | goal "
      "|\n|---|---|---|---|---|\n",
      big.words(), fs::file_size(file) / 1e6);
  g_results["vocab_load_1m_ms_median"] = median(load_ms);
  g_results["transform_2000_random_1m_ms_median"] = median(transform_ms);
  std::printf("| load (ms) | %.1f | %.1f | %.1f | <= 30 |\n", median(load_ms),
              *std::min_element(load_ms.begin(), load_ms.end()),
              *std::max_element(load_ms.begin(), load_ms.end()));
  std::printf("| transform 2000 descriptors (ms) | %.3f | %.3f | %.3f | <= 0.5 |\n", median(transform_ms),
              *std::min_element(transform_ms.begin(), transform_ms.end()),
              *std::max_element(transform_ms.begin(), transform_ms.end()));
  fs::remove(file);
  // The same on a trained vocabulary with real descriptors: real descriptors follow the tree's clusters,
  // so the descent touches far fewer distinct nodes than random ones (which miss the cache at every level).
  const std::string real_img = "../shared/data/kitti/sample_00/image_0/000000.png";
  if (fs::exists("vocab/kitti08/hbow.bin") && fs::exists(real_img)) {
    const auto voc = HbowRecognizer::loadVocabulary("vocab/kitti08/hbow.bin");
    ExtractOptions eo;
    eo.orb.features = 2000;
    const Descriptors real = extractDescriptors({real_img}, eo).front();
    std::vector<double> ms;
    BowVector bow;
    for (int r = 0; r < runs; ++r) {
      const auto t = Clock::now();
      for (int i = 0; i < 50; ++i) voc->transform(real, &bow);
      ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t).count() / 50);
    }
    g_results["transform_2000_ms_median"] = median(ms);
    std::printf(
        "| transform %zu real KITTI descriptors, vocab/kitti08/hbow.bin (k=10, L=6, %zu words) (ms) | %.3f | "
        "%.3f | %.3f | <= 0.5 |\n",
        real.size(), voc->words(), median(ms), *std::min_element(ms.begin(), ms.end()),
        *std::max_element(ms.begin(), ms.end()));
  }
}

void queryBench(const std::string& only_model) {
  const int runs = kRuns;
  const std::string vocab_dir = fs::exists("vocab/kitti08") ? "vocab/kitti08" : "";
  if (vocab_dir.empty()) {
    std::printf("\nvocab/kitti08 not found (run from the repository root): query benchmark skipped\n");
    return;
  }
  const int n = 1500;
  const auto kfs = keyframes(n);
  std::printf(
      "\n| model (vocab/kitti08) | query vs %d keyframes, median ms | p95 ms | signature ms | index "
      "bytes/keyframe | goal ms |\n|---|---|---|---|---|---|\n",
      n);
  const std::map<std::string, double> goal{
      {"hbow", 1}, {"fabmap", 10}, {"vlad", 0.1}, {"hmvlad", 0.1}, {"vladpq", 0.1}};
  for (const auto& name : placeModelNames()) {
    if (!only_model.empty() && name != only_model) continue;
    const std::string model_file = vocab_dir + "/" + name + ".bin";
    if (!fs::exists(model_file)) {
      std::printf("| %s | (no %s: make it with vocab/make_vocab.sh) | | | | |\n", name.c_str(),
                  model_file.c_str());
      continue;
    }
    auto rec = makePlaceRecognizer(name, {model_file});
    rec->setKeepDescriptors(false);
    std::vector<double> sig;
    for (int i = 0; i < n; ++i) sig.push_back(rec->add(i, kfs[i]));
    std::vector<double> per_run, all;
    std::map<std::string, std::vector<double>> steps;
    for (int r = 0; r < runs; ++r) {
      std::vector<double> q;
      for (int i = 0; i < 20; ++i) {
        const KeyframeId id = static_cast<KeyframeId>(n - 1 - (r * 20 + i) * 7);
        QueryScope scope;
        scope.reference = {id - 1, id - 2, id - 3};
        const QueryResult res = rec->query(id, scope);
        q.push_back(res.total_ms);
        for (const auto& st : res.timings) steps[st.step].push_back(st.ms);
      }
      per_run.push_back(median(q));
      all.insert(all.end(), q.begin(), q.end());
    }
    std::string breakdown;
    for (const auto& [step, ms] : steps)
      breakdown += " " + step + " " + std::to_string(median(ms)).substr(0, 6);
    std::fprintf(stderr, "%s steps (median ms):%s\n", name.c_str(), breakdown.c_str());
    std::sort(all.begin(), all.end());
    const double p95 = all[static_cast<size_t>(0.95 * (all.size() - 1))];
    g_results[name + "_query_1500x2000_ms_median"] = median(per_run);
    g_results[name + "_query_1500x2000_ms_p95"] = p95;
    std::printf("| %s | %.4f | %.4f | %.2f | %zu | <= %g |\n", name.c_str(), median(per_run), p95,
                median(sig), rec->indexBytesPerKeyframe(), goal.at(name));
  }
}

}  // namespace

// bench_place_bench [vocab|query [model]]: one part (the query part for one model), or both.
int main(int argc, char** argv) {
  cv::setNumThreads(1);
  const std::string only = argc > 1 ? argv[1] : "";
  if (only.empty() || only == "vocab") vocabularyBench();
  if (only.empty() || only == "query") queryBench(argc > 2 ? argv[2] : "");
  JsonObject record = bench::machineRecord();
  record.add("runs", 9);
  for (const auto& [k, v] : g_results) record.add(k, v);
  std::printf("\nwrote %s\n", bench::writeRecord(record, ".build/bench/place.json").c_str());
  return 0;
}
