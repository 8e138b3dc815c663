#pragma once
// The keys of an (unordered) map in ascending order: what a state file is written in, so that two saves of
// the same state give the same bytes whatever order the hash map holds them in.
#include <algorithm>
#include <vector>

namespace binloop {

template <class Map>
std::vector<typename Map::key_type> sortedKeys(const Map& m) {
  std::vector<typename Map::key_type> k;
  k.reserve(m.size());
  for (const auto& e : m) k.push_back(e.first);
  std::sort(k.begin(), k.end());
  return k;
}

}  // namespace binloop
