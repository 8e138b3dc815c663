#pragma once
// A number with a fixed count of decimals, for the one-line details and messages the stages report.
#include <cstdio>
#include <string>

namespace binloop {

inline std::string fixedDecimals(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

}  // namespace binloop
