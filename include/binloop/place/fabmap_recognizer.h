#pragma once
// `fabmap` (thesis chapter 3, binary FAB-MAP): keyframes are word-presence sets of a flat vocabulary.
// A query (1) pre-filters by the L2 distance of normalised presence vectors: only keyframes closer than the
// closest reference keyframe plus an offset go on (thesis fig. 3.9); (2) evaluates p(Z|L) with the Chow-Liu
// tree and the detector model (eq. 3.12-3.16) for them and for the reference keyframes; (3) normalises
// with the new-place evidence, mean-field (3.18) or sampled (3.19), a uniform prior with `p_new` on the
// new place, and smoothing sigma (3.20). Candidates are keyframes whose posterior beats every reference's.
//
// A candidate's `confidence`, which ranks it against other queries' candidates, is its log-likelihood
// ratio against the new-place evidence, log p(Z|L) - log p(Z|new), in nats. The posterior cannot rank
// across queries: it saturates at ~1 for the best place and its size follows how many places passed the
// gate. The likelihood ratio says how much better the place explains the query than an unseen place does
// (docs/loop_models.md, "Ranking loops"). The closest keyframes by L2 beyond the gate are ranked too
// (never passed), so that a query whose references are closer than its loop still names its best guess.
//
// p(z|e, z_parent) depends on four binary states per word, so it is tabulated once per model; a query
// then costs one pass over the vocabulary plus one pass over the words of each evaluated keyframe.
#include <array>
#include <memory>
#include <unordered_map>
#include <utility>
#include <vector>

#include "binloop/place/chow_liu_tree.h"
#include "binloop/place/flat_vocabulary.h"
#include "binloop/place/place_recognizer.h"

namespace binloop {

struct FabmapParams {
  double p_z_given_e = 0.39;     // detector: p(z = 1 | e = 1)
  double p_z_given_not_e = 0.0;  // detector: p(z = 1 | e = 0)
  double p_new = 0.9;            // prior mass of a new place
  double sigma = 0.99;           // smoothing (eq. 3.20)
  bool sampled_evidence = true;  // false: mean-field average place
  double l2_offset = 0.05;       // added to the closest reference's L2 distance in the pre-filter
};

struct FabmapModel {
  std::shared_ptr<const FlatVocabulary> vocabulary;
  std::shared_ptr<const ChowLiuTree> tree;
  std::vector<std::vector<uint32_t>> samples;  // presence sets of training places (sampled evidence)
  FabmapParams params;
  static FabmapModel load(const std::string& path);
  void write(ModelWriter& w) const;
};

class FabmapRecognizer : public PlaceRecognizer {
 public:
  explicit FabmapRecognizer(FabmapModel model);
  std::string name() const override { return "fabmap"; }
  size_t indexBytesPerKeyframe() const override;
  /// log p(Z_query | L_k) for a stored keyframe k (tests check it against the direct formula).
  double logLikelihood(KeyframeId query, KeyframeId k) const;
  /// log p(z | L) by the direct sum over all words (slow; for tests).
  double logLikelihoodDirect(const std::vector<uint32_t>& query, const std::vector<uint32_t>& place) const;

 protected:
  void addSignature(Slot slot, const Descriptors& d) override;
  QueryResult querySignature(const SlotScope& scope) const override;

 private:
  FabmapModel m_;
  // log p(z_i = zq | z_parent = zp, L) for L's observation of word i = lz, indexed [i][zq][zp][lz]; and the
  // same for the mean-field average place, [i][zq][zp].
  std::vector<std::array<float, 8>> log_term_;
  std::vector<std::array<float, 4>> log_avg_;
  std::vector<std::vector<uint32_t>> words_;  // per slot: the words it saw
  std::vector<std::vector<Slot>> inverted_;   // per word
  struct QueryTables {
    double base = 0;           // sum over words of the term for a place that saw none of them
    std::vector<float> delta;  // per word: term(seen) - term(not seen)
    double avg = 0;            // mean-field new place
  };
  // Keyframes beyond the L2 gate whose likelihood is evaluated for ranking: the closest ones by L2.
  static constexpr size_t kRankedBeyondGate = 20;
  QueryTables tables(const std::vector<uint32_t>& query) const;
  static double placeLogLik(const QueryTables& t, const std::vector<uint32_t>& place);
  /// log p(Z | new place): the training samples' mean likelihood (3.19), or the mean-field place (3.18).
  double newPlaceLogLik(const QueryTables& t) const;
  void rankBeyondGate(QueryResult& r, const QueryTables& t, double new_place,
                      std::vector<std::pair<double, Slot>> beyond) const;
  /// Smoothed posterior over `loglik`'s places and, last, the new place.
  std::vector<double> posterior(const std::vector<double>& loglik, double new_place) const;
};

}  // namespace binloop
