#pragma once
// The ORB-extraction options every tool that reads images offers (--features, --max-side, --grid-cell,
// --threads). One declaration, so that a vocabulary trained by `train` and queried by `eval-loops` is
// fed by the same extractor unless the user asks otherwise.
#include "binloop/features/image_features.h"
#include "binloop/util/cli_args.h"

namespace binloop {

void declareExtractOptions(CliArgs& args);
/// The options as parsed; skip_unreadable and skipped stay for the caller.
ExtractOptions extractOptionsFrom(const CliArgs& args);

}  // namespace binloop
