// descriptor-stats: how balanced and independent the extractor's 256 bits are on a set of images, for each
// BRIEF pattern (features/descriptor_statistics.h). One table row per pattern.
#include <iomanip>
#include <iostream>
#include <sstream>

#include "binloop/features/descriptor_statistics.h"
#include "binloop/features/extract_options_cli.h"
#include "binloop/features/image_features.h"
#include "binloop/place/place_error.h"
#include "binloop/util/cli_args.h"

int main(int argc, char** argv) {
  binloop::CliArgs args("descriptor-stats",
                        "descriptor-stats --images <dir>... [--patterns orb,gaussian] [options]");
  args.option("images", "folder of images or KITTI-layout sequence (image_0/ is used); repeat for more")
      .option("every", "use every n-th image of each folder", "1")
      .option("patterns", "comma list of BRIEF patterns to compare (--pattern is ignored)", "orb,gaussian")
      .option("seed", "seed of the random descriptor pairs", "1")
      .flag("skip-unreadable", "skip images that cannot be read as 8-bit instead of stopping");
  binloop::declareExtractOptions(args);
  return binloop::runTool("descriptor-stats", [&] {
    if (!args.parse(argc, argv)) return 0;
    if (!args.has("images")) throw binloop::CliError("--images is required");
    binloop::ExtractOptions eo = binloop::extractOptionsFrom(args);
    const long every = args.integer("every");
    if (every < 1) throw binloop::CliError("--every must be >= 1");
    std::vector<std::string> paths;
    for (const auto& dir : args.all("images")) {
      const auto files = binloop::listImages(dir);
      for (size_t i = 0; i < files.size(); i += every) paths.push_back(files[i]);
    }
    std::cout << "| pattern | images | descriptors | mean abs(P(1) - 0.5) | median abs(corr) | mean "
                 "abs(corr) | max abs(corr) "
                 "| random pairs, bits apart |\n|---|---|---|---|---|---|---|---|\n";
    eo.skip_unreadable = args.has("skip-unreadable");
    std::stringstream list(args.str("patterns"));
    bool first_row = true;  // unreadable images are the same for every pattern: say so once
    for (std::string name; std::getline(list, name, ','); first_row = false) {
      try {
        eo.orb.pattern = binloop::briefPatternFromName(name);
      } catch (const binloop::PlaceError& e) {
        throw binloop::CliError(std::string("--patterns: ") + e.what());
      }
      std::vector<std::string> skipped;
      eo.skipped = &skipped;
      binloop::Descriptors all;
      for (const auto& d : binloop::extractDescriptors(paths, eo)) all.insert(all.end(), d.begin(), d.end());
      if (first_row)
        for (const auto& why : skipped) std::cerr << "descriptor-stats: skipped " << why << "\n";
      const size_t images = paths.size() - skipped.size();
      if (images == 0) throw binloop::CliError("no readable images");
      const binloop::BitStatistics s =
          binloop::bitStatistics(all, static_cast<uint64_t>(args.integer("seed")));
      std::cout << std::fixed << std::setprecision(3) << "| " << name << " | " << images << " | "
                << s.descriptors << " | " << s.mean_bias << " | " << s.median_abs_correlation << " | "
                << s.mean_abs_correlation << " | " << s.max_abs_correlation << " | " << std::setprecision(1)
                << s.random_pair_distance << " |\n";
    }
    return 0;
  });
}
