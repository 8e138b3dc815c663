#pragma once
// The feature-extraction options every tool that reads images offers (--features, --scale-factor,
// --pyramid-levels, --ini-fast, --min-fast, --cell-px, --max-side, --threads). One declaration, with the
// SLAM's extractor settings as defaults, so that a vocabulary trained by `train` and queried by `eval-loops`
// (or the SLAM) is fed by the same extractor unless the user asks otherwise.
#include "binloop/features/image_features.h"
#include "binloop/util/cli_args.h"

namespace binloop {

void declareExtractOptions(CliArgs& args);
/// The options as parsed; skip_unreadable and skipped stay for the caller. Throws CliError for settings
/// the extractor refuses (naming the option) and for the retired --grid-cell.
ExtractOptions extractOptionsFrom(const CliArgs& args);

}  // namespace binloop
