#pragma once
// One PNG chart with the precision-recall curves of several models (OpenCV drawing, no plotting library).
#include <string>
#include <vector>

#include "binloop/eval/loop_metrics.h"

namespace binloop {

struct PrSeries {
  std::string label;
  std::vector<PrPoint> curve;
};

/// Throws DataError when the file cannot be written.
void writePrPlot(const std::string& path, const std::string& title, const std::vector<PrSeries>& series);

}  // namespace binloop
