#pragma once
// Milliseconds since a steady-clock instant: how every stage times its steps.
#include <chrono>

namespace binloop {

inline double msSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace binloop
