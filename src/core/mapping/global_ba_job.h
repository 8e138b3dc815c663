#pragma once
// LocalMapper's background global BA (local_mapper_ba.cpp), complete wherever LocalMapper is made or
// destroyed.
#include <atomic>
#include <string>
#include <thread>

#include "binloop/mapping/local_mapper.h"

namespace binloop {

// The job's thread sees only its own copy of the problem (which keeps the starting poses and points);
// mapping goes on with the map meanwhile.
struct LocalMapper::GlobalBaJob {
  BaSetup setup;
  uint64_t seq_at_start = 0;  // keyframes inserted after it were added meanwhile
  LocalBaResult result;
  std::atomic<bool> abort{false}, done{false};
  std::string failure;  // what it threw, if it did (written before done)
  std::thread thread;
};

}  // namespace binloop
