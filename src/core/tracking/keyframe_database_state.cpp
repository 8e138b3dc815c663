// KeyframeDatabase's save/load (tracking's state file).
#include "binloop/io/state_file.h"
#include "binloop/tracking/keyframe_database.h"
#include "binloop/util/sorted_keys.h"

namespace binloop {

void KeyframeDatabase::save(StateWriter& w) const {
  w.put<uint64_t>(bows_.size());
  for (SlamKeyframeId id : sortedKeys(bows_)) {
    w.put<uint64_t>(id);
    const BowVector& b = bows_.at(id);
    w.put<uint64_t>(b.size());
    for (const BowEntry& e : b) {
      w.put(e.word);
      w.put(e.value);
    }
  }
}

void KeyframeDatabase::load(StateReader& r) {
  bows_.clear();
  inverted_.clear();
  const uint64_t n = r.getCount("relocalisation index", 16);
  for (uint64_t i = 0; i < n; ++i) {
    const SlamKeyframeId id = r.get<uint64_t>("relocalisation keyframe");
    BowVector b(r.getCount("bag of words", 8));
    for (BowEntry& e : b) {
      e.word = r.get<uint32_t>("word");
      e.value = r.get<float>("word weight");
      if (voc_ && e.word >= voc_->words())
        r.fail("word " + std::to_string(e.word) + " is not in the vocabulary");
    }
    for (const BowEntry& e : b) inverted_[e.word].push_back(id);
    bows_[id] = std::move(b);
  }
}

}  // namespace binloop
