#pragma once
// LoopCandidates: loop detection -> loop closing (and the logs), one per keyframe and model queried. It says
// what the model proposed, whether the consistency check accepted one of the proposals, and, when nothing
// was proposed, why. Maps 1:1 onto binloop/LoopCandidates.
#include <memory>
#include <string>
#include <vector>

#include "binloop/map/ids.h"

namespace binloop::msg {

struct LoopCandidate {
  SlamKeyframeId id = kNoId;
  double score = 0;       // the model's own score
  double confidence = 0;  // comparable across queries (place/ranking.h)
};

struct LoopStepTime {
  std::string step;
  double ms = 0;
};

struct LoopCandidates {
  SlamKeyframeId query = kNoId;
  uint64_t query_frame = 0;
  std::string model;                      // hbow, fabmap, vlad, hmvlad, vladpq
  bool shadow = false;                    // true: logged only, never acted on
  std::string status;                     // the model's query status (found, below_reference, ...)
  std::string detail;                     // the numbers behind it, one line
  std::vector<LoopCandidate> candidates;  // passed the model's bar, best first
  int consistency = 0;                    // consecutive consistent queries of the strongest chain so far
  SlamKeyframeId accepted = kNoId;        // the candidate the consistency check accepted, if any
  // With an accepted candidate and a model that has them (PlaceRecognizer::matchWords): a coarse word per
  // keypoint of the query and of the accepted keyframe, so that verification matches within words.
  std::vector<uint32_t> query_words, accepted_words;
  std::vector<LoopStepTime> timings;  // "signature" first (adding the keyframe), then the query's steps
  double total_ms = 0;                // signature + query
};
using LoopCandidatesPtr = std::shared_ptr<const LoopCandidates>;

}  // namespace binloop::msg
