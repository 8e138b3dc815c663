// train: trains a place-recognition model (vocabulary) from images, or imports a DBoW2 vocabulary
// (see docs/loop_models.md).
#include <chrono>
#include <filesystem>
#include <iostream>

#include "binloop/features/extract_options_cli.h"
#include "binloop/features/image_features.h"
#include "binloop/place/dbow2_import.h"
#include "binloop/place/model_training.h"
#include "binloop/util/cli_args.h"
#include "binloop/util/progress_bar.h"

int main(int argc, char** argv) {
  binloop::CliArgs args(
      "train",
      "train <hbow|fabmap|vlad|hmvlad|vladpq> --images <dir|sequence_dir>... --out <model.bin> [options]\n"
      "       train hbow --import <ORBvoc.txt|voc.yml.gz> --out <model.bin>");
  args.positional("model", "model type")
      .option("images", "folder of images or KITTI-layout sequence (image_0/ is used); repeat for more")
      .option("every", "use every n-th image of each folder", "1")
      .option("out", "model file to write")
      .option("import", "DBoW2 vocabulary to convert instead of training (hbow only)")
      .option("k", "branching factor / words (default: the model's thesis size)", "0")
      .option("levels", "tree levels (default: the model's thesis size)", "0")
      .option("words", "fabmap flat vocabulary size", "10000")
      .option("pq-codes", "vladpq codebook size per word", "32")
      .option("pca", "VLAD LCS-PCA dimensions per word (0 = off)", "0")
      .option("max-descriptors", "descriptors sampled for flat and VLAD vocabularies", "200000")
      .option("seed", "training seed", "1")
      .flag("skip-unreadable", "skip images that cannot be read as 8-bit (say which) instead of stopping");
  binloop::declareExtractOptions(args);
  return binloop::runTool("train", [&] {
    if (!args.parse(argc, argv)) return 0;
    const auto type = binloop::modelTypeFromName(args.str("model"));
    if (!args.has("out")) throw binloop::CliError("--out is required");
    // The folder of the model file is made, as `run --out` makes its own.
    const std::filesystem::path out_dir = std::filesystem::path(args.str("out")).parent_path();
    if (!out_dir.empty()) std::filesystem::create_directories(out_dir);
    const auto t0 = std::chrono::steady_clock::now();
    if (args.has("import")) {
      if (type != binloop::ModelType::kHbow) throw binloop::CliError("--import makes hbow models only");
      const auto tree = binloop::importDbow2(args.str("import"));
      binloop::ModelHeader h;
      h.extractor.kind = binloop::ExtractorKind::kDbow2Import;  // another BRIEF pattern than binloop's
      binloop::saveHbowModel(tree, h, args.str("out"));
      std::cout << "imported " << args.str("import") << ": k=" << tree.k() << " L=" << tree.levels() << ", "
                << tree.words() << " words -> " << args.str("out") << "\n";
      return 0;
    }
    if (!args.has("images")) throw binloop::CliError("--images (or --import) is required");
    binloop::ExtractOptions eo = binloop::extractOptionsFrom(args);
    std::vector<std::string> paths;
    const long every = args.integer("every");
    if (every < 1) throw binloop::CliError("--every must be >= 1");
    for (const auto& dir : args.all("images")) {
      const auto files = binloop::listImages(dir);
      for (size_t i = 0; i < files.size(); i += every) paths.push_back(files[i]);
    }
    std::vector<std::string> skipped;
    eo.skip_unreadable = args.has("skip-unreadable");
    eo.skipped = &skipped;
    std::vector<binloop::Descriptors> images;
    {
      binloop::ProgressBar bar("ORB features", paths.size());
      images = binloop::extractDescriptors(paths, eo, [&](size_t d, size_t n) { bar.update(d, n); });
    }
    for (const auto& s : skipped) std::cerr << "train: skipped " << s << "\n";
    binloop::TrainOptions o;
    o.k = static_cast<int>(args.integer("k"));
    o.levels = static_cast<int>(args.integer("levels"));
    o.words = static_cast<int>(args.integer("words"));
    o.pq_codes = static_cast<int>(args.integer("pq-codes"));
    o.pca_dims = static_cast<int>(args.integer("pca"));
    o.seed = static_cast<uint64_t>(args.integer("seed"));
    o.max_descriptors = static_cast<size_t>(args.integer("max-descriptors"));
    o.extractor = binloop::extractorSettings(eo);  // recorded in the header; loaders compare it
    binloop::ProgressBar bar("training " + args.str("model"));
    const auto h =
        binloop::trainModel(type, images, o, args.str("out"), [&](size_t d, size_t n) { bar.update(d, n); });
    bar.finish();
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::cout << args.str("out") << ": " << h.describe() << "; " << paths.size() << " images, " << s
              << " s\n";
    return 0;
  });
}
