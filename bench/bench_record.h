#pragma once
// What every benchmark's .json file starts with (when and on what it ran), and where it goes: the path in
// $BINLOOP_BENCH_JSON (scripts/bench.sh sets .build/bench/<name>.json), else `fallback`.
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "binloop/util/json_object.h"

namespace binloop::bench {

inline std::string cpuModel() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  return "unknown";
}

/// date (UTC), cpu and cores, for the caller to add its numbers to.
inline JsonObject machineRecord() {
  char date[32];
  const std::time_t now = std::time(nullptr);
  std::strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
  JsonObject o;
  o.add("date", std::string(date)).add("cpu", cpuModel()).add("cores", std::thread::hardware_concurrency());
  return o;
}

/// Writes `record` where $BINLOOP_BENCH_JSON says (else `fallback`), making its folder; returns the path.
inline std::string writeRecord(const JsonObject& record, const std::string& fallback) {
  const char* env = std::getenv("BINLOOP_BENCH_JSON");
  const std::filesystem::path path = env ? env : fallback;
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
  std::ofstream(path) << record.str();
  return path.string();
}

}  // namespace binloop::bench
