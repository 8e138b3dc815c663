#pragma once
// Local mapping's autosave: its state file (the map save's format, written durably: io/state_file.h) every
// `every` keyframes and after each loop correction and global BA merge, so that a process that dies and is
// respawned resumes the map instead of starting an empty one (the only stage whose state no other stage
// holds whole; tracking then sends the keyframes made after the save again: tracking/tracking_stage.h).
//
// It resumes only an autosave of its own session, a name the launch gives each graph it starts and its
// respawns keep: an autosave an earlier graph left behind is not a map this graph's other stages know.
//
// The map is serialised on the caller's thread and written (with fsync) on another, so mapping waits only
// for the copy. A map grows to ~150 KB a keyframe (370 keyframes of rendered route 06: 54 MB, written in a
// quarter of a second), so saves are also spaced so that they take at most `max_share` of the time: a save
// is skipped while the last one is still being written or less than last_ms / max_share has passed.
// Not thread-safe: one caller (local mapping's callbacks).
#include <chrono>
#include <cstdint>
#include <future>
#include <memory>
#include <string>

#include "binloop/mapping/local_mapper.h"

namespace binloop {

class MapAutosave {
 public:
  /// `every` <= 0: off. `session`: names this graph; empty: resumes nothing.
  MapAutosave(std::string path, int every, std::string session, double max_share = 0.05);
  /// Waits for a write in progress.
  ~MapAutosave();
  MapAutosave(const MapAutosave&) = delete;
  MapAutosave& operator=(const MapAutosave&) = delete;

  bool on() const { return every_ > 0; }
  const std::string& path() const { return path_; }
  /// The session's map id in the state file's header (never 0 for a named session).
  uint64_t mapId() const { return map_id_; }

  /// A mapper loaded from this session's autosave (LocalMapper::resumeAfterRestart done), or null when there
  /// is none, it is another session's, or it cannot be read; `note` says which.
  std::unique_ptr<LocalMapper> resume(const LocalMapperParams& p, std::string* note) const;
  /// After a keyframe: starts a save at every `every`-th (or the first one after, when spaced out); true
  /// when it started one. Throws DataError for the last write's failure.
  bool afterKeyframe(const LocalMapper& m);
  /// Starts a save now (after a correction or a global BA merge), when on and not spaced out (then the next
  /// keyframe saves); true when it started one. Throws DataError for the last write's failure.
  bool save(const LocalMapper& m);
  /// Saves now and returns once the file is written, however recent the last save (after a loop correction,
  /// before its update goes out: a process respawned from an autosave then never lacks a correction that
  /// tracking has applied, which would leave tracking's later keyframes in a frame the map is not in).
  /// Throws DataError for this write's or the last one's failure.
  void saveBeforeGoingOn(const LocalMapper& m);
  /// Waits for the write in progress. Throws DataError for its failure.
  void wait();

  uint64_t saves() const { return saves_; }
  /// Of the last save: serialising plus writing, and the file's payload.
  double lastMs() const { return last_ms_; }
  size_t lastBytes() const { return last_bytes_; }

 private:
  std::string path_;
  int every_;
  std::string session_;
  uint64_t map_id_;
  double max_share_;
  uint64_t keyframes_ = 0, saves_ = 0;
  bool due_ = false;  // a keyframe save was skipped: the next keyframe saves
  double last_ms_ = 0, serialise_ms_ = 0;
  size_t last_bytes_ = 0;
  std::chrono::steady_clock::time_point last_start_;
  std::future<double> writing_;  // the write's ms

  bool spacedOut();                  // collects a finished write
  void start(const LocalMapper& m);  // serialises here, writes on another thread
  void collect();
};

}  // namespace binloop
