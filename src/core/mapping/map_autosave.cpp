#include "binloop/mapping/map_autosave.h"

#include <chrono>
#include <filesystem>
#include <utility>

#include "binloop/io/state_file.h"
#include "binloop/util/stopwatch.h"

namespace binloop {

namespace {

constexpr const char* kStage = "local_mapping";

// FNV-1a: the same session name gives the same id in every process, unlike std::hash.
uint64_t sessionId(const std::string& session) {
  if (session.empty()) return 0;
  uint64_t h = 14695981039346656037ull;
  for (unsigned char c : session) h = (h ^ c) * 1099511628211ull;
  return h ? h : 1;
}

}  // namespace

MapAutosave::MapAutosave(std::string path, int every, std::string session, double max_share)
    : path_(std::move(path)),
      every_(every),
      session_(std::move(session)),
      map_id_(sessionId(session_)),
      max_share_(max_share) {}

MapAutosave::~MapAutosave() {
  try {
    wait();
  } catch (const std::exception&) {  // nobody is left to tell; the last good autosave stays
  }
}

std::unique_ptr<LocalMapper> MapAutosave::resume(const LocalMapperParams& p, std::string* note) const {
  auto none = [note](std::string why) -> std::unique_ptr<LocalMapper> {
    *note = std::move(why);
    return nullptr;
  };
  if (!on()) return none("autosave off");
  if (session_.empty()) return none("no session name: nothing to resume");
  std::error_code ec;
  if (!std::filesystem::exists(path_, ec)) return none("no autosave at " + path_);
  try {
    if (stateFileMapId(path_, kStage) != map_id_) {
      return none("the autosave at " + path_ + " is another graph's (not session '" + session_ +
                  "'): not resumed, and overwritten at the next save");
    }
    auto m = std::make_unique<LocalMapper>(p);
    loadStateFile(*m, path_, kStage);
    m->resumeAfterRestart();
    *note = "resumed " + std::to_string(m->keyframeCount()) + " keyframes and " +
            std::to_string(m->pointCount()) + " map points from the autosave at " + path_;
    return m;
  } catch (const std::exception& e) {
    return none(std::string("the autosave could not be read, starting an empty map: ") + e.what());
  }
}

bool MapAutosave::afterKeyframe(const LocalMapper& m) {
  if (!on()) return false;
  if (++keyframes_ % static_cast<uint64_t>(every_) == 0) due_ = true;
  return due_ && save(m);
}

bool MapAutosave::spacedOut() {
  if (writing_.valid()) {
    if (writing_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return true;
    collect();
  }
  if (saves_ == 0 || max_share_ <= 0) return false;
  return msSince(last_start_) < last_ms_ / max_share_;
}

void MapAutosave::collect() {
  if (writing_.valid()) last_ms_ = serialise_ms_ + writing_.get();  // rethrows the write's DataError
}

void MapAutosave::wait() { collect(); }

bool MapAutosave::save(const LocalMapper& m) {
  if (!on()) return false;
  if (spacedOut()) {
    due_ = true;  // a loop or a global BA skipped here is saved at the next keyframe that may
    return false;
  }
  start(m);
  return true;
}

void MapAutosave::saveBeforeGoingOn(const LocalMapper& m) {
  if (!on()) return;
  collect();  // the write in progress first: the files are written in order
  start(m);
  collect();
}

void MapAutosave::start(const LocalMapper& m) {
  due_ = false;
  last_start_ = std::chrono::steady_clock::now();
  const std::filesystem::path dir = std::filesystem::path(path_).parent_path();
  std::error_code ec;
  if (!dir.empty()) std::filesystem::create_directories(dir, ec);  // a failure shows in the write's error
  auto w = std::make_shared<StateWriter>(path_, kStage, map_id_);
  m.save(*w);
  serialise_ms_ = msSince(last_start_);
  last_ms_ = serialise_ms_;
  last_bytes_ = w->size();
  writing_ = std::async(std::launch::async, [w] {
    const auto t0 = std::chrono::steady_clock::now();
    w->finish();
    return msSince(t0);
  });
  ++saves_;
}

}  // namespace binloop
