#pragma once
// loops.csv: the runner's log of loop detection and closing, one row per keyframe and model queried (the
// active model's row also carries what loop closing made of its proposal), plus a row per held loop that
// expired. eval-slam reads the accepted loops back from it.
#include <string>
#include <vector>

#include "binloop/pipeline/slam_pipeline.h"

namespace binloop {

void writeLoopLog(const std::string& path, const std::vector<SlamPipeline::LoopLogEntry>& log);

struct LoggedLoop {
  std::string model, status;
  uint64_t query_frame = 0, match_frame = 0;
  int inliers = 0;
  double correction_m = 0;
};
/// Every row of loops.csv that names a verified loop (accepted, held, or rejected by closing).
/// Throws DataError for a missing file or a malformed row.
std::vector<LoggedLoop> readLoopLog(const std::string& path);

}  // namespace binloop
