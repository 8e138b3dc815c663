#include "binloop/features/extract_options_cli.h"

#include <string>

namespace binloop {

void declareExtractOptions(CliArgs& args) {
  const OrbParams orb;
  args.option("features", "ORB features per image", std::to_string(orb.features))
      .option("max-side", "scale larger images down to this longer side (0 = never)", "1024")
      .option("grid-cell", "spread ORB features over a grid of cells this many pixels wide (0 = strongest first)",
              std::to_string(orb.grid_cell_px))
      .option("threads", "feature extraction threads", std::to_string(ExtractOptions{}.threads));
}

ExtractOptions extractOptionsFrom(const CliArgs& args) {
  ExtractOptions eo;
  eo.orb.features = static_cast<int>(args.integer("features"));
  eo.orb.grid_cell_px = static_cast<int>(args.integer("grid-cell"));
  eo.max_side = static_cast<int>(args.integer("max-side"));
  eo.threads = static_cast<int>(args.integer("threads"));
  return eo;
}

}  // namespace binloop
