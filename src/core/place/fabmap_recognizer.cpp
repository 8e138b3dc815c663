#include "binloop/place/fabmap_recognizer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "binloop/place/place_error.h"
#include "binloop/place/slot_counter.h"

namespace binloop {

namespace {

double logSumExp(const std::vector<double>& v) {
  double m = -std::numeric_limits<double>::infinity();
  for (double x : v) m = std::max(m, x);
  double s = 0;
  for (double x : v) s += std::exp(x - m);
  return m + std::log(s);
}

}  // namespace

FabmapModel FabmapModel::load(const std::string& path) {
  ModelReader r(path);
  r.expectType(ModelType::kFabmap);
  FabmapModel m;
  const auto par = r.section<double>("FPAR");
  if (par.size() != 6) throw PlaceError(path + ": FAB-MAP parameter section malformed");
  m.params = {par[0], par[1], par[2], par[3], par[4] != 0, par[5]};
  m.vocabulary = std::make_shared<FlatVocabulary>(r.section<Desc256>("FVOC"));
  m.tree = std::make_shared<ChowLiuTree>(ChowLiuTree::read(r));
  const auto offsets = r.section<uint64_t>("FSMO");
  const auto ids = r.section<uint32_t>("FSMW");
  for (size_t i = 0; i + 1 < offsets.size(); ++i) {
    if (offsets[i] > offsets[i + 1] || offsets[i + 1] > ids.size())
      throw PlaceError(path + ": FAB-MAP samples malformed");
    m.samples.emplace_back(ids.begin() + offsets[i], ids.begin() + offsets[i + 1]);
  }
  r.expectEnd();
  if (m.tree->words() != m.vocabulary->size()) {
    throw PlaceError(path + ": Chow-Liu tree has " + std::to_string(m.tree->words()) + " words, vocabulary " +
                     std::to_string(m.vocabulary->size()));
  }
  return m;
}

void FabmapModel::write(ModelWriter& w) const {
  w.section("FPAR", std::vector<double>{params.p_z_given_e, params.p_z_given_not_e, params.p_new,
                                        params.sigma, params.sampled_evidence ? 1.0 : 0.0, params.l2_offset});
  w.section("FVOC", vocabulary->words());
  tree->write(w);
  std::vector<uint64_t> offsets{0};
  std::vector<uint32_t> ids;
  for (const auto& s : samples) {
    ids.insert(ids.end(), s.begin(), s.end());
    offsets.push_back(ids.size());
  }
  w.section("FSMO", offsets);
  w.section("FSMW", ids);
}

FabmapRecognizer::FabmapRecognizer(FabmapModel model) : m_(std::move(model)) {
  if (!m_.vocabulary || !m_.tree) throw PlaceError("fabmap: no model");
  const FabmapParams& p = m_.params;
  const uint32_t n = m_.tree->words();
  log_term_.resize(n);
  log_avg_.resize(n);
  auto pz_e = [&](bool z, bool e) {  // detector p(z | e)
    const double p1 = e ? p.p_z_given_e : p.p_z_given_not_e;
    return z ? p1 : 1 - p1;
  };
  for (uint32_t i = 0; i < n; ++i) {
    const double marg = m_.tree->marginal(i);
    for (int zq = 0; zq < 2; ++zq) {
      for (int zp = 0; zp < 2; ++zp) {
        const double cond1 = m_.tree->conditional(i, zp);
        const double pz_zp = zq ? cond1 : 1 - cond1, pnz_zp = 1 - pz_zp;
        const double pz = zq ? marg : 1 - marg, pnz = 1 - pz;
        double given_e[2];  // p(z_i = zq | e_i = e, z_parent = zp), eq. 3.14-3.16
        for (int e = 0; e < 2; ++e) {
          const double alpha = pz * pz_e(!zq, e) * pnz_zp;
          const double beta = pnz * pz_e(zq, e) * pz_zp;
          given_e[e] = beta > 0 ? 1.0 / (1.0 + alpha / beta) : 0.0;
        }
        for (int lz = 0; lz < 2; ++lz) {
          // p(e_i = 1 | L) from the place's single observation lz, with the marginal as prior.
          const double a = pz_e(lz, true) * marg, b = pz_e(lz, false) * (1 - marg);
          const double pe1 = a + b > 0 ? a / (a + b) : 0.0;
          const double term = given_e[1] * pe1 + given_e[0] * (1 - pe1);
          log_term_[i][zq * 4 + zp * 2 + lz] = static_cast<float>(std::log(std::max(term, 1e-300)));
        }
        const double avg = given_e[1] * marg + given_e[0] * (1 - marg);
        log_avg_[i][zq * 2 + zp] = static_cast<float>(std::log(std::max(avg, 1e-300)));
      }
    }
  }
  inverted_.resize(n);
}

FabmapRecognizer::QueryTables FabmapRecognizer::tables(const std::vector<uint32_t>& query) const {
  const uint32_t n = m_.tree->words();
  std::vector<uint8_t> z(n, 0);
  for (uint32_t w : query) z[w] = 1;
  QueryTables t;
  t.delta.resize(n);
  for (uint32_t i = 0; i < n; ++i) {
    const int zq = z[i], zp = z[m_.tree->parent(i)];
    const auto& lt = log_term_[i];
    t.base += lt[zq * 4 + zp * 2];
    t.delta[i] = lt[zq * 4 + zp * 2 + 1] - lt[zq * 4 + zp * 2];
    t.avg += log_avg_[i][zq * 2 + zp];
  }
  return t;
}

double FabmapRecognizer::placeLogLik(const QueryTables& t, const std::vector<uint32_t>& place) {
  double s = t.base;
  for (uint32_t w : place) s += t.delta[w];
  return s;
}

double FabmapRecognizer::logLikelihood(KeyframeId query, KeyframeId k) const {
  return placeLogLik(tables(words_[slotOf(query)]), words_[slotOf(k)]);
}

double FabmapRecognizer::logLikelihoodDirect(const std::vector<uint32_t>& query,
                                             const std::vector<uint32_t>& place) const {
  const uint32_t n = m_.tree->words();
  std::vector<char> z(n, 0), l(n, 0);
  for (uint32_t w : query) z[w] = 1;
  for (uint32_t w : place) l[w] = 1;
  double s = 0;
  for (uint32_t i = 0; i < n; ++i) s += log_term_[i][z[i] * 4 + z[m_.tree->parent(i)] * 2 + l[i]];
  return s;
}

void FabmapRecognizer::addSignature(Slot slot, const Descriptors& d) {
  words_.push_back(m_.vocabulary->presence(d));
  for (uint32_t x : words_.back()) inverted_[x].push_back(slot);
}

size_t FabmapRecognizer::indexBytesPerKeyframe() const {
  if (words_.empty()) return 0;
  size_t n = 0;
  for (const auto& w : words_) n += w.size();
  return n * (sizeof(uint32_t) + sizeof(KeyframeId)) / words_.size();  // presence list + inverted entries
}

double FabmapRecognizer::newPlaceLogLik(const QueryTables& t) const {
  if (!m_.params.sampled_evidence || m_.samples.empty()) return t.avg;
  std::vector<double> s;
  s.reserve(m_.samples.size());
  for (const auto& smp : m_.samples) s.push_back(placeLogLik(t, smp));
  return logSumExp(s) - std::log(double(s.size()));
}

void FabmapRecognizer::rankBeyondGate(QueryResult& r, const QueryTables& t, double new_place,
                                      std::vector<std::pair<double, Slot>> beyond) const {
  const size_t n = std::min(beyond.size(), kRankedBeyondGate);
  std::partial_sort(beyond.begin(), beyond.begin() + static_cast<std::ptrdiff_t>(n), beyond.end());
  for (size_t i = 0; i < n; ++i) {
    const Slot k = beyond[i].second;
    offer(r, {idAt(k), 0.0, placeLogLik(t, words_[k]) - new_place}, false);
  }
}

QueryResult FabmapRecognizer::querySignature(const SlotScope& scope) const {
  QueryResult r;
  const auto& q = words_[scope.query];
  auto t = std::chrono::steady_clock::now();
  SlotCounter common(words_.size());
  for (uint32_t w : q) common.add(inverted_[w]);
  auto l2 = [&](Slot k) {
    return std::sqrt(std::max(0.0, 2.0 - 2.0 * common[k] / std::sqrt(double(q.size()) * words_[k].size())));
  };
  const std::vector<Slot>& refs = scope.reference;
  if (refs.empty()) {
    r.status = QueryStatus::kNoReference;
    r.detail = "no reference keyframe in the database";
    return r;
  }
  double min_l2 = std::numeric_limits<double>::max();
  for (Slot k : refs) min_l2 = std::min(min_l2, l2(k));
  std::vector<Slot> pre;
  std::vector<std::pair<double, Slot>> beyond;  // outside the gate: ranked, never passed
  for (Slot k : common.touched()) {             // the query itself too; scope.excluded drops it
    if (scope.excluded[k]) continue;
    const double d = l2(k);
    if (d < min_l2 + m_.params.l2_offset) {
      pre.push_back(k);
    } else {
      beyond.emplace_back(d, k);
    }
  }
  r.timings.push_back({"l2_prefilter", msSince(t)});

  t = std::chrono::steady_clock::now();
  const QueryTables tab = tables(q);
  const double new_place = newPlaceLogLik(tab);
  rankBeyondGate(r, tab, new_place, std::move(beyond));
  if (pre.empty()) {
    r.status = QueryStatus::kNoPreCandidates;
    r.detail =
        "no keyframe within L2 " + std::to_string(min_l2) + " + " + std::to_string(m_.params.l2_offset);
    return r;
  }
  std::vector<double> loglik;  // references, then pre-candidates
  loglik.reserve(refs.size() + pre.size());
  for (Slot k : refs) loglik.push_back(placeLogLik(tab, words_[k]));
  for (Slot k : pre) loglik.push_back(placeLogLik(tab, words_[k]));
  r.timings.push_back({"likelihood", msSince(t)});

  t = std::chrono::steady_clock::now();
  const std::vector<double> post = posterior(loglik, new_place);
  const size_t places = loglik.size();
  double bar = 0;
  for (size_t i = 0; i < refs.size(); ++i) bar = std::max(bar, post[i]);
  r.threshold = bar;
  std::vector<Candidate> all;
  for (size_t j = 0; j < pre.size(); ++j) {
    const double p = post[refs.size() + j];
    const Candidate c{idAt(pre[j]), p, loglik[refs.size() + j] - new_place};
    offer(r, c, p > bar);
    if (scope.max_ranked) all.push_back(c);
  }
  sortCandidates(r);
  if (scope.max_ranked) keepRanked(r, std::move(all), scope.max_ranked);
  r.timings.push_back({"posterior", msSince(t)});
  std::ostringstream detail;
  detail << pre.size() << " within L2 " << min_l2 << "+" << m_.params.l2_offset
         << "; best reference posterior " << bar << ", new place " << post[places] << "; "
         << r.candidates.size() << " beat it";
  r.detail = detail.str();
  r.status = r.candidates.empty() ? QueryStatus::kBelowReference : QueryStatus::kFound;
  return r;
}

std::vector<double> FabmapRecognizer::posterior(const std::vector<double>& loglik, double new_place) const {
  const size_t places = loglik.size();
  std::vector<double> logpost(places + 1);
  const double log_prior_place = std::log((1 - m_.params.p_new) / double(places));
  for (size_t i = 0; i < places; ++i) logpost[i] = loglik[i] + log_prior_place;
  logpost[places] = new_place + std::log(m_.params.p_new);
  const double norm = logSumExp(logpost);
  std::vector<double> post(places + 1);
  for (size_t i = 0; i <= places; ++i) {
    post[i] = m_.params.sigma * std::exp(logpost[i] - norm) + (1 - m_.params.sigma) / double(places + 1);
  }
  return post;
}

}  // namespace binloop
