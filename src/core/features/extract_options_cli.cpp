#include "binloop/features/extract_options_cli.h"

#include <sstream>
#include <string>

#include "binloop/features/feature_error.h"

namespace binloop {

void declareExtractOptions(CliArgs& args) {
  const ExtractOptions d;
  std::ostringstream scale;
  scale << d.orb.scale_factor;
  args.option("features", "ORB features per image", std::to_string(d.orb.features))
      .option("scale-factor", "ORB pyramid scale between levels", scale.str())
      .option("pyramid-levels", "ORB pyramid levels", std::to_string(d.orb.levels))
      .option("ini-fast", "FAST threshold tried first in each cell", std::to_string(d.orb.ini_fast))
      .option("min-fast", "FAST threshold where a cell found nothing", std::to_string(d.orb.min_fast))
      .option("cell-px", "FAST cell side, level pixels", std::to_string(d.orb.cell_px))
      .option("pattern",
              "BRIEF tests: gaussian (binloop's, as the SLAM by default) or orb (ORB's learned rBRIEF)",
              briefPatternName(d.orb.pattern))
      .option("max-side", "scale larger images down to this longer side first (0 = never, as the SLAM)",
              std::to_string(d.max_side))
      .option("threads", "feature extraction threads", std::to_string(d.threads))
      .option("grid-cell",
              "retired (the OpenCV-ORB grid extractor is gone; every tool uses the SLAM's extractor)");
}

ExtractOptions extractOptionsFrom(const CliArgs& args) {
  if (args.has("grid-cell")) {
    throw CliError(
        "--grid-cell is retired: every tool now extracts with the SLAM's ORB extractor (quadtree spread, "
        "--cell-px sets its FAST cells); see docs/loop_models.md, \"Features\"");
  }
  ExtractOptions eo;
  eo.orb.features = static_cast<int>(args.integer("features"));
  eo.orb.scale_factor = static_cast<float>(args.number("scale-factor"));
  eo.orb.levels = static_cast<int>(args.integer("pyramid-levels"));
  eo.orb.ini_fast = static_cast<int>(args.integer("ini-fast"));
  eo.orb.min_fast = static_cast<int>(args.integer("min-fast"));
  eo.orb.cell_px = static_cast<int>(args.integer("cell-px"));
  eo.max_side = static_cast<int>(args.integer("max-side"));
  try {
    eo.orb.pattern = briefPatternFromName(args.str("pattern"));
  } catch (const FeatureError& e) {
    throw CliError(std::string("--pattern: ") + e.what());
  }
  eo.threads = static_cast<int>(args.integer("threads"));
  if (eo.max_side < 0) throw CliError("--max-side must be >= 0, got " + std::to_string(eo.max_side));
  try {
    OrbSlamExtractor check(eo.orb);  // refuses out-of-range settings now, not after reading images
  } catch (const FeatureError& e) {
    throw CliError(std::string("extractor options: ") + e.what());
  }
  return eo;
}

}  // namespace binloop
