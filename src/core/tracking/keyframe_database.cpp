#include "binloop/tracking/keyframe_database.h"

#include <algorithm>

namespace binloop {

KeyframeDatabase::KeyframeDatabase(std::shared_ptr<const VocabularyTree> voc) : voc_(std::move(voc)) {}

void KeyframeDatabase::add(SlamKeyframeId id, const Descriptors& d) {
  if (bows_.count(id) || d.empty()) return;
  BowVector b;
  voc_->transform(d, &b);
  for (const BowEntry& e : b) inverted_[e.word].push_back(id);
  bows_.emplace(id, std::move(b));
}

void KeyframeDatabase::remove(SlamKeyframeId id) {
  auto it = bows_.find(id);
  if (it == bows_.end()) return;
  for (const BowEntry& e : it->second) {
    auto& list = inverted_[e.word];
    list.erase(std::remove(list.begin(), list.end(), id), list.end());
  }
  bows_.erase(it);
}

std::vector<SlamKeyframeId> KeyframeDatabase::candidates(const Descriptors& d, size_t max,
                                                         const NeighboursFn& neighbours) const {
  if (bows_.empty() || d.empty() || max == 0) return {};
  BowVector q;
  voc_->transform(d, &q);
  std::unordered_map<SlamKeyframeId, int> common;
  for (const BowEntry& e : q) {
    auto it = inverted_.find(e.word);
    if (it == inverted_.end()) continue;
    for (SlamKeyframeId k : it->second) ++common[k];
  }
  if (common.empty()) return {};
  int most = 0;
  for (const auto& [k, c] : common) most = std::max(most, c);
  const int min_common = static_cast<int>(0.8 * most);
  std::unordered_map<SlamKeyframeId, double> score;
  for (const auto& [k, c] : common)
    if (c >= min_common) score[k] = l1Score(q, bows_.at(k));

  struct Group {
    double sum;
    SlamKeyframeId best;
    double best_score;
  };
  std::vector<Group> groups;
  double best_sum = 0;
  for (const auto& [k, s] : score) {
    Group g{s, k, s};
    for (SlamKeyframeId n : neighbours(k)) {
      auto it = score.find(n);
      if (it == score.end()) continue;
      g.sum += it->second;
      if (it->second > g.best_score) g.best_score = it->second, g.best = n;
    }
    best_sum = std::max(best_sum, g.sum);
    groups.push_back(g);
  }
  // Highest sum first; ties by id so that the order never depends on the hash map's.
  std::sort(groups.begin(), groups.end(),
            [](const Group& a, const Group& b) { return a.sum != b.sum ? a.sum > b.sum : a.best < b.best; });
  std::vector<SlamKeyframeId> out;
  for (const Group& g : groups) {
    if (g.sum < 0.75 * best_sum || out.size() >= max) break;
    if (std::find(out.begin(), out.end(), g.best) == out.end()) out.push_back(g.best);
  }
  return out;
}

}  // namespace binloop
