#pragma once
// The one interface of the five loop models (hbow, fabmap, vlad, hmvlad, vladpq). SLAM and the
// evaluation tool both drive it the same way: add() a keyframe's descriptors, then query() that keyframe
// with its scope — the reference keyframes (covisible neighbours in SLAM, the previous few keyframes on
// an image sequence) whose scores set the bar, and the keyframes that must be ignored. A query says
// which candidates passed, the bar it used, why nothing passed if so, and how long each step took.
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "binloop/place/model_file.h"
#include "binloop/place/ranking.h"
#include "binloop/types/binary_descriptor.h"
#include "binloop/util/stopwatch.h"

namespace binloop {

using KeyframeId = uint32_t;

struct QueryScope {
  std::vector<KeyframeId> reference;  // set the bar; never candidates
  std::vector<KeyframeId> ignore;     // never candidates
  /// When > 0, the result also lists (in `ranked`) up to this many keyframes outside the scope by the
  /// model's raw score, passed or not: for logs and for studies of how to rank loops.
  size_t max_ranked = 0;
};

enum class QueryStatus {
  kFound,            // candidates holds at least one keyframe
  kUnknownKeyframe,  // the query keyframe was never added
  kEmptyDatabase,    // nothing outside the scope to compare with
  kNoReference,      // no reference keyframe in the database: no bar can be set
  kNoPreCandidates,  // the pre-filter (common words, L2, short signature, shared codes) left nothing
  kBelowReference,   // every candidate scored worse than the reference bar
};
std::string statusName(QueryStatus s);

struct Candidate {
  KeyframeId id = 0;
  double score = 0;  // the model's own score (similarity, negative distance, or probability)
  /// Comparable across queries, higher = likelier a true loop (place/ranking.h). Whether the keyframe
  /// beat the query's own bar is said by where it is: in `candidates` (beat it) or `best_rejected`.
  double confidence = 0;
};

struct StepTime {
  std::string step;
  double ms = 0;
};

struct QueryResult {
  QueryStatus status = QueryStatus::kEmptyDatabase;
  std::string detail;                 // one line for logs: the numbers behind the status
  std::vector<Candidate> candidates;  // best first
  double threshold = 0;               // the bar, in the model's score units
  /// The best keyframe that did not pass the bar or the pre-filter, when there was one; an evaluation
  /// ranks it with the candidates of other queries.
  bool has_best_rejected = false;
  Candidate best_rejected;
  std::vector<StepTime> timings;
  double total_ms = 0;
  /// Only with QueryScope::max_ranked > 0: the best keyframes the model scored, by raw score, best first.
  std::vector<Candidate> ranked;
  /// The query's prediction: the first candidate, else the best rejected keyframe, else none.
  const Candidate* best() const {
    return !candidates.empty() ? &candidates.front() : has_best_rejected ? &best_rejected : nullptr;
  }
};

class PlaceRecognizer {
 public:
  virtual ~PlaceRecognizer() = default;
  virtual std::string name() const = 0;
  /// Computes and stores the keyframe's signature; returns the milliseconds spent on the signature.
  /// Throws PlaceError for an empty descriptor set or an id added before.
  double add(KeyframeId id, const Descriptors& d);
  QueryResult query(KeyframeId id, const QueryScope& scope) const;
  size_t size() const { return order_.size(); }
  /// Memory of signatures and index per keyframe (the vocabulary is not counted).
  virtual size_t indexBytesPerKeyframe() const = 0;
  /// A coarse word per descriptor, for loop verification to match descriptors only within a word
  /// (ORB-SLAM2's SearchByBoW); empty when the model has no vocabulary fit for it (the default).
  virtual std::vector<uint32_t> matchWords(const Descriptors& d) const { return {}; }
  /// The descriptors given to add(), kept so another model can be rebuilt from them.
  const Descriptors& descriptors(KeyframeId id) const;
  const std::vector<KeyframeId>& keyframes() const { return order_; }
  /// Adds every stored keyframe, in order, to `other` (switching models at run time).
  void rebuildInto(PlaceRecognizer& other) const;
  /// Who counts as a keyframe's group for hbow's score accumulation (SLAM: covisible keyframes).
  /// Default: keyframes added within 2 positions of it.
  using GroupFn = std::function<std::vector<KeyframeId>(KeyframeId)>;
  void setGroupFunction(GroupFn f) { group_fn_ = std::move(f); }
  void setKeepDescriptors(bool keep) { keep_descriptors_ = keep; }
  void setRanking(const RankingParams& r) { ranking_ = r; }
  const RankingParams& ranking() const { return ranking_; }

 protected:
  /// A keyframe's position in add order. Models keep signatures in vectors indexed by slot, so a query
  /// scans contiguous memory and tests exclusion with one array lookup instead of a hash per keyframe.
  using Slot = uint32_t;
  /// What a model's query works with, resolved once by query(): the query's slot, the slots of the
  /// reference keyframes that are in the database, how many the scope named, and per slot whether it
  /// may not be a candidate (the query itself, its reference and ignored keyframes).
  struct SlotScope {
    Slot query = 0;
    std::vector<Slot> reference;
    size_t reference_named = 0;
    std::vector<char> excluded;
    size_t max_ranked = 0;
  };
  /// Stores the signature of the keyframe that will get `slot` (== size() before the add). Must leave
  /// the model unchanged when it throws.
  virtual void addSignature(Slot slot, const Descriptors& d) = 0;
  virtual QueryResult querySignature(const SlotScope& scope) const = 0;
  KeyframeId idAt(Slot s) const { return order_[s]; }
  /// Throws PlaceError for an id that was never added.
  Slot slotOf(KeyframeId id) const;
  bool findSlot(KeyframeId id, Slot* s) const;
  std::vector<KeyframeId> group(KeyframeId id) const;
  /// Files `c` as a candidate when it passes the bar, else keeps it if it is the best rejected so far.
  static void offer(QueryResult& r, const Candidate& c, bool passes);
  /// Best score first; equal scores by id, so that results do not depend on hash-map order.
  static void sortCandidates(QueryResult& r);
  /// Keeps the `n` best of `all` (by score, ties by id) as r.ranked.
  static void keepRanked(QueryResult& r, std::vector<Candidate> all, size_t n);
  bool known(KeyframeId id) const { return position_.count(id) > 0; }

 private:
  std::vector<KeyframeId> order_;
  std::unordered_map<KeyframeId, Slot> position_;
  std::unordered_map<KeyframeId, Descriptors> descriptors_;
  GroupFn group_fn_;
  bool keep_descriptors_ = true;
  RankingParams ranking_;
};

struct RecognizerOptions {
  std::string model_file;          // the trained model (vocabulary) of this model type
  double fabmap_l2_offset = 0.05;  // see FabmapRecognizer
  double hbow_min_bar = 0.005;     // see HbowRecognizer
  int vladpq_shared_slack = 8;     // see VladPqRecognizer
  int vlad_reference_rank = 3;     // see VladRecognizer, HmvladRecognizer, VladPqRecognizer
  RankingParams ranking{};
  /// The extractor whose descriptors add() will get (extractor.expected; e.g.
  /// extractorSettings(OrbSlamParams) from features/orb_slam_extractor.h) and what to do when the model
  /// file was trained on others: see checkModelExtractor. Unset (unknown) = no check.
  ExtractorCheck extractor{};
};

/// `name` is one of hbow, fabmap, vlad, hmvlad, vladpq; throws PlaceError for another name, or when the
/// model file is missing, of another model type, truncated or corrupt, or (when opts.extractor.expected
/// is set and force is not) trained on descriptors of another extractor or other settings.
std::unique_ptr<PlaceRecognizer> makePlaceRecognizer(const std::string& name, const RecognizerOptions& opts);
const std::vector<std::string>& placeModelNames();

}  // namespace binloop
