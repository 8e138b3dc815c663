#pragma once
// A stage's saved state (the map save/load services): one file per stage, so that each stage saves and loads
// only what it owns, in whichever process it runs. Layout: a 32-byte header (magic "BLSTATE1", format
// version, payload size, payload checksum, the stage's name length), the stage's name, the id of the map save
// it belongs to (io/map_folder.h: every stage's file of one save carries the same), then the payload: plain
// little-endian numbers, strings and arrays written field by field (never a struct's bytes, whose padding
// would make two saves of one state differ).
//
// Written to <path>.partial, flushed to disk (fsync) and renamed when complete, so an interrupted save never
// leaves a half file under the real name. A reader checks magic, version, stage and checksum before the
// stage sees a byte, and names the field it was reading when a file ends early; every error is a DataError
// naming the file.
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include "binloop/io/data_error.h"

namespace binloop {

/// Where stage `stage` keeps its state in a saved map folder: <directory>/<stage>.state. The stages are
/// "tracking", "local_mapping", "loop_detector" and "loop_closing".
std::string stageStatePath(const std::string& directory, const std::string& stage);

class StateWriter {
 public:
  // 2: loop closing keeps its culled keyframes' parents; 3: the map id after the stage's name (the payload
  // is version 2's, so version 2 files are read too, with map id 0).
  static constexpr uint32_t kVersion = 3;
  /// The stage name is checked on load ("tracking", "local_mapping", ...); `map_id` names the save.
  StateWriter(std::string path, std::string stage, uint64_t map_id);

  template <class T>
  void put(T v) {
    static_assert(std::is_arithmetic_v<T> || std::is_enum_v<T>, "put numbers; write structs field by field");
    const size_t at = bytes_.size();
    bytes_.resize(at + sizeof(T));
    std::memcpy(bytes_.data() + at, &v, sizeof(T));
  }
  void putString(const std::string& s);
  /// An array of numbers (or of fixed-size number records such as Desc256) as a count and raw bytes.
  template <class T>
  void putArray(const std::vector<T>& v) {
    static_assert(std::has_unique_object_representations_v<T> || std::is_floating_point_v<T>,
                  "putArray needs types without padding");
    put<uint64_t>(v.size());
    const size_t at = bytes_.size();
    bytes_.resize(at + v.size() * sizeof(T));
    if (!v.empty()) std::memcpy(bytes_.data() + at, v.data(), v.size() * sizeof(T));
  }

  /// Writes <path>.partial, syncs it to disk and renames it to <path>. Throws DataError when the folder is
  /// not writable or the disk is full.
  void finish();
  size_t size() const { return bytes_.size(); }

 private:
  std::string path_, stage_;
  uint64_t map_id_;
  std::vector<uint8_t> bytes_;
};

/// The map id in the header of stage `stage`'s state file `path`, reading the header only (0 for a file
/// from before map ids). Throws DataError as StateReader does for the header.
uint64_t stateFileMapId(const std::string& path, const std::string& stage);

class StateReader {
 public:
  /// Reads and checks the whole file. Throws DataError for a missing, truncated or corrupt file, another
  /// format version, or another stage's file.
  StateReader(std::string path, const std::string& stage);

  template <class T>
  T get(const char* what) {
    static_assert(std::is_arithmetic_v<T> || std::is_enum_v<T>, "get numbers");
    T v;
    std::memcpy(&v, take(sizeof(T), what), sizeof(T));
    return v;
  }
  std::string getString(const char* what);
  template <class T>
  std::vector<T> getArray(const char* what) {
    const uint64_t n = get<uint64_t>(what);
    if (n > (bytes_.size() - pos_) / sizeof(T)) fail(std::string("truncated in ") + what);
    std::vector<T> v(n);
    if (n) std::memcpy(v.data(), take(n * sizeof(T), what), n * sizeof(T));
    return v;
  }
  /// A count of records that follow, checked against the bytes left (each at least `min_record_bytes`), so a
  /// corrupt count cannot make a reader allocate gigabytes.
  uint64_t getCount(const char* what, size_t min_record_bytes = 1);
  /// Throws unless every byte was read (a file written by other code).
  void expectEnd();
  [[noreturn]] void fail(const std::string& what) const;
  const std::string& path() const { return path_; }
  uint64_t mapId() const { return map_id_; }

 private:
  const uint8_t* take(size_t n, const char* what);

  std::string path_;
  uint64_t map_id_ = 0;
  std::vector<uint8_t> bytes_;
  size_t pos_ = 0;
};

/// Writes a stage (anything with save(StateWriter&)) into its state file `path` as stage `name` of map save
/// `map_id`; returns the payload bytes written.
template <class Stage>
size_t saveStateFile(const Stage& s, const std::string& path, const std::string& name, uint64_t map_id) {
  StateWriter w(path, name, map_id);
  s.save(w);
  w.finish();
  return w.size();
}

/// Loads the state file `path` of stage `name` into `s` (a newly made stage); returns the file's map id.
/// Throws DataError.
template <class Stage>
uint64_t loadStateFile(Stage& s, const std::string& path, const std::string& name) {
  StateReader r(path, name);
  s.load(r);
  return r.mapId();
}

}  // namespace binloop
