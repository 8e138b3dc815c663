#include "binloop/place/vocabulary_tree.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <string>

#include "binloop/place/k_majority.h"
#include "binloop/util/hash_random.h"

namespace binloop {

struct VocabularyTree::Owned {
  std::vector<Desc256> desc;
  std::vector<uint32_t> first_child, child_count;
  std::vector<float> weight;
};

void VocabularyTree::adopt(std::shared_ptr<Owned> o) {
  desc_ = {o->desc.data(), o->desc.size()};
  first_child_ = {o->first_child.data(), o->first_child.size()};
  child_count_ = {o->child_count.data(), o->child_count.size()};
  weight_ = {o->weight.data(), o->weight.size()};
  storage_ = std::move(o);
  indexWords();
}

VocabularyTree VocabularyTree::train(const std::vector<Descriptors>& images, const VocabTreeParams& p,
                                     const ProgressFn& progress) {
  if (p.k < 2 || p.levels < 1) throw PlaceError("vocabulary tree needs k >= 2 and levels >= 1");
  Descriptors data;
  for (const auto& im : images) data.insert(data.end(), im.begin(), im.end());
  const size_t min_needed = static_cast<size_t>(p.k) * 10;
  if (data.size() < min_needed) {
    throw PlaceError("too few descriptors to train a k=" + std::to_string(p.k) + " vocabulary tree: " +
                     std::to_string(data.size()) + " (need at least " + std::to_string(min_needed) + ")");
  }
  VocabularyTree t;
  t.k_ = p.k;
  t.levels_ = p.levels;
  t.weighting_ = p.weighting;
  auto o = std::make_shared<Owned>();
  // Breadth-first: each queue entry is a node waiting for its children, with its descriptors.
  struct Pending {
    uint32_t node;
    int depth;
    std::vector<uint32_t> idx;
  };
  o->desc.push_back(Desc256{});
  o->first_child.push_back(0);
  o->child_count.push_back(0);
  std::deque<Pending> queue;
  {
    std::vector<uint32_t> all(data.size());
    for (size_t i = 0; i < all.size(); ++i) all[i] = static_cast<uint32_t>(i);
    queue.push_back({0, 0, std::move(all)});
  }
  const size_t total_work = data.size() * static_cast<size_t>(p.levels);
  size_t done_work = 0;
  while (!queue.empty()) {
    Pending cur = std::move(queue.front());
    queue.pop_front();
    KMajorityParams kp{p.k, p.max_iterations, hashCombine(p.seed, cur.node)};
    KMajorityResult km = kMajority(data, cur.idx, kp);
    const auto first = static_cast<uint32_t>(o->desc.size());
    o->first_child[cur.node] = first;
    o->child_count[cur.node] = static_cast<uint32_t>(km.centres.size());
    std::vector<std::vector<uint32_t>> members(km.centres.size());
    for (size_t i = 0; i < cur.idx.size(); ++i) members[km.assignment[i]].push_back(cur.idx[i]);
    for (size_t c = 0; c < km.centres.size(); ++c) {
      o->desc.push_back(km.centres[c]);
      o->first_child.push_back(0);
      o->child_count.push_back(0);
      // A cluster of one descriptor cannot be split further: it stays a leaf above the bottom level.
      if (cur.depth + 1 < p.levels && members[c].size() > 1) {
        queue.push_back({first + static_cast<uint32_t>(c), cur.depth + 1, std::move(members[c])});
      } else {
        done_work += members[c].size() * static_cast<size_t>(p.levels - cur.depth - 1);
      }
    }
    done_work += cur.idx.size();
    if (progress) progress(done_work, total_work);
  }
  // Weights are filled in by computeIdf once the words are known; the view is re-pointed after it.
  o->weight.assign(std::count(o->child_count.begin() + 1, o->child_count.end(), 0u), 1.0f);
  const auto owned = o;
  t.adopt(std::move(o));
  if (t.words() < static_cast<size_t>(p.k)) {
    throw PlaceError("degenerate vocabulary: only " + std::to_string(t.words()) + " distinct words from " +
                     std::to_string(data.size()) + " descriptors");
  }
  owned->weight = t.computeIdf(images);
  t.weight_ = {owned->weight.data(), owned->weight.size()};
  return t;
}

void VocabularyTree::indexWords() {
  node_word_.assign(desc_.size, UINT32_MAX);
  word_node_.clear();
  for (uint32_t n = 1; n < desc_.size; ++n) {
    if (child_count_[n] == 0) {
      node_word_[n] = static_cast<uint32_t>(word_node_.size());
      word_node_.push_back(n);
    }
  }
}

std::vector<float> VocabularyTree::computeIdf(const std::vector<Descriptors>& images) const {
  std::vector<uint32_t> df(words(), 0), last_seen(words(), UINT32_MAX);
  for (uint32_t im = 0; im < images.size(); ++im) {
    for (const auto& d : images[im]) {
      const uint32_t w = wordOf(d);
      if (last_seen[w] != im) last_seen[w] = im, df[w]++;
    }
  }
  std::vector<float> weight(words());
  const double n = static_cast<double>(std::max<size_t>(1, images.size()));
  for (size_t w = 0; w < words(); ++w) {
    const bool uses_idf = weighting_ == Weighting::kTfIdf || weighting_ == Weighting::kIdf;
    weight[w] = uses_idf ? static_cast<float>(std::log(n / std::max<uint32_t>(1, df[w]))) : 1.0f;
  }
  return weight;
}

VocabularyTree VocabularyTree::fromNodes(int k, int levels, Weighting w, const std::vector<InputNode>& in) {
  if (in.empty()) throw PlaceError("vocabulary has no nodes");
  std::vector<std::vector<uint32_t>> children(in.size());
  for (uint32_t i = 1; i < in.size(); ++i) {
    if (in[i].parent >= in.size() || in[i].parent == i) {
      throw PlaceError("vocabulary node " + std::to_string(i) + " has an invalid parent " +
                       std::to_string(in[i].parent));
    }
    children[in[i].parent].push_back(i);
  }
  VocabularyTree t;
  t.k_ = k;
  t.levels_ = levels;
  t.weighting_ = w;
  auto o = std::make_shared<Owned>();
  std::vector<uint32_t> order{0};  // input index of each output node, breadth first
  o->desc.push_back(Desc256{});
  o->first_child.push_back(0);
  o->child_count.push_back(0);
  for (size_t pos = 0; pos < order.size(); ++pos) {
    const auto& ch = children[order[pos]];
    if (ch.size() > 0 && in[order[pos]].is_leaf && pos != 0) {
      throw PlaceError("vocabulary node " + std::to_string(order[pos]) +
                       " is marked as a word but has children");
    }
    o->first_child[pos] = static_cast<uint32_t>(order.size());
    o->child_count[pos] = static_cast<uint32_t>(ch.size());
    for (uint32_t c : ch) {
      order.push_back(c);
      o->desc.push_back(in[c].descriptor);
      o->first_child.push_back(0);
      o->child_count.push_back(0);
    }
    if (order.size() > in.size()) throw PlaceError("vocabulary nodes form a cycle");
  }
  if (order.size() != in.size()) {
    throw PlaceError("vocabulary has " + std::to_string(in.size() - order.size()) +
                     " nodes not reachable from the root");
  }
  for (uint32_t n = 1; n < o->desc.size(); ++n)
    if (o->child_count[n] == 0) o->weight.push_back(in[order[n]].weight);
  t.adopt(std::move(o));
  if (t.words() == 0) throw PlaceError("vocabulary has no words");
  return t;
}

uint32_t VocabularyTree::wordOf(const Desc256& d, int node_depth, uint32_t* path_node) const {
  const uint32_t at = nodeOf(d, node_depth);
  if (path_node) *path_node = at;
  return node_word_[nodeOf(d, std::numeric_limits<int>::max(), at)];  // on down to the leaf
}

uint32_t VocabularyTree::nodeOf(const Desc256& d, int depth, uint32_t from) const {
  uint32_t n = from;
  for (int level = 0; level < depth && child_count_[n] != 0; ++level)
    n = first_child_[n] + nearestCentre(d, &desc_[first_child_[n]], child_count_[n]);
  return n;
}

void VocabularyTree::descend(const Desc256* d, size_t n, int fv_depth, uint32_t* word,
                             uint32_t* fv_node) const {
  // Descriptors go down the tree in lanes of kLanes, one level at a time: while a lane compares itself
  // with its children, the children blocks of the other lanes are already being fetched. Below the
  // cached top levels every step is a cache miss, so overlapping them is what makes a 1M-word tree fast.
  constexpr size_t kLanes = 16;
  uint32_t node[kLanes];
  for (size_t base = 0; base < n; base += kLanes) {
    const size_t lanes = std::min(kLanes, n - base);
    for (size_t l = 0; l < lanes; ++l) {
      node[l] = 0;
      if (fv_node) fv_node[base + l] = 0;
    }
    for (int depth = 1, active = static_cast<int>(lanes); active > 0; ++depth) {
      active = 0;
      for (size_t l = 0; l < lanes; ++l) {
        const uint32_t nd = node[l];
        if (child_count_[nd] == 0) continue;
        const uint32_t first = first_child_[nd];
        const uint32_t next = first + nearestCentre(d[base + l], &desc_[first], child_count_[nd]);
        node[l] = next;
        if (fv_node && depth == fv_depth) fv_node[base + l] = next;
        if (child_count_[next] != 0) {
          // Fetch the grandchildren's descriptors and the children's own links for the next level.
          const uint32_t gc = first_child_[next], count = child_count_[next];
          const char* p = reinterpret_cast<const char*>(&desc_[gc]);
          for (size_t b = 0; b < count * sizeof(Desc256); b += 64) __builtin_prefetch(p + b);
          __builtin_prefetch(&first_child_[gc]);
          __builtin_prefetch(&first_child_[gc + count - 1]);
          __builtin_prefetch(&child_count_[gc]);
          __builtin_prefetch(&child_count_[gc + count - 1]);
          ++active;
        } else if (fv_node && depth < fv_depth) {
          fv_node[base + l] = next;  // a shallow leaf stands for its own subtree
        }
      }
    }
    for (size_t l = 0; l < lanes; ++l) word[base + l] = node_word_[node[l]];
  }
}

void VocabularyTree::transform(const Descriptors& d, BowVector* bow, FeatureVector* fv, int fv_depth) const {
  std::vector<uint32_t> word(d.size()), fv_node(fv ? d.size() : 0);
  descend(d.data(), d.size(), fv_depth, word.data(), fv ? fv_node.data() : nullptr);
  std::vector<std::pair<uint32_t, uint32_t>> words(d.size());  // (word, feature)
  for (size_t i = 0; i < d.size(); ++i) words[i] = {word[i], static_cast<uint32_t>(i)};
  std::sort(words.begin(), words.end());
  bow->clear();
  const bool once = weighting_ == Weighting::kIdf || weighting_ == Weighting::kBinary;
  for (size_t i = 0; i < words.size();) {
    size_t j = i;
    while (j < words.size() && words[j].first == words[i].first) ++j;
    const float wgt = weight_[words[i].first];
    if (wgt > 0) bow->push_back({words[i].first, once ? wgt : wgt * static_cast<float>(j - i)});
    i = j;
  }
  normalizeL1(*bow);
  if (fv) {
    std::vector<std::pair<uint32_t, uint32_t>> nodes(d.size());
    for (size_t i = 0; i < d.size(); ++i) nodes[i] = {fv_node[i], static_cast<uint32_t>(i)};
    std::sort(nodes.begin(), nodes.end());
    fv->clear();
    for (const auto& [node, feat] : nodes) {
      if (fv->empty() || fv->back().first != node) fv->push_back({node, {}});
      fv->back().second.push_back(feat);
    }
  }
}

void VocabularyTree::write(ModelWriter& w) const {
  w.raw("TDSC", sizeof(Desc256), desc_.size, desc_.data);
  w.raw("TFCH", sizeof(uint32_t), first_child_.size, first_child_.data);
  w.raw("TNCH", sizeof(uint32_t), child_count_.size, child_count_.data);
  w.raw("TWGT", sizeof(float), weight_.size, weight_.data);
}

VocabularyTree VocabularyTree::read(ModelReader& r) {
  VocabularyTree t;
  t.k_ = static_cast<int>(r.header().k);
  t.levels_ = static_cast<int>(r.header().levels);
  t.weighting_ = r.header().weighting;
  t.desc_ = r.view<Desc256>("TDSC");
  t.first_child_ = r.view<uint32_t>("TFCH");
  t.child_count_ = r.view<uint32_t>("TNCH");
  t.weight_ = r.view<float>("TWGT");
  t.storage_ = r.storage();
  const size_t n = t.desc_.size;
  if (n == 0 || t.first_child_.size != n || t.child_count_.size != n)
    throw PlaceError(r.path() + ": vocabulary tree sections disagree on the node count");
  for (size_t i = 0; i < n; ++i) {
    if (t.child_count_[i] && (t.first_child_[i] <= i || t.first_child_[i] + t.child_count_[i] > n))
      throw PlaceError(r.path() + ": vocabulary tree node " + std::to_string(i) + " points outside the tree");
  }
  t.indexWords();
  if (t.weight_.size != t.words()) {
    throw PlaceError(r.path() + ": " + std::to_string(t.weight_.size) + " word weights for " +
                     std::to_string(t.words()) + " words");
  }
  return t;
}

}  // namespace binloop
