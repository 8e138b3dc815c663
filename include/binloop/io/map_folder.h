#pragma once
// A saved map is a folder of the stages' state files (state_file.h) that belong together. Saving and loading
// it are transactions, whether the stages run in one process or in four:
// - every file of one save carries the save's map id, so a folder mixing files of two saves is refused;
// - a save writes a new folder beside the destination and swaps it in only when every stage has written
//   (each file flushed to disk, then the folder renamed in one step), so a failed or interrupted save leaves
//   the old map whole;
// - a load checks every stage's file before any stage changes (checkMapFolder here; the stages then load
//   into new objects and are swapped in only when all have loaded).
#include <cstdint>
#include <string>
#include <vector>

#include "binloop/io/data_error.h"

namespace binloop {

/// A new map id: never 0, and different for every call, in this process and across processes (the clock,
/// the process id and a counter, hashed). Identifies a save; it takes no part in what the map holds.
uint64_t newMapId();

/// One save of a map into `directory`.
class MapSave {
 public:
  /// Makes the staging folder <directory>.saving-<id> beside `directory`. Throws DataError when `directory`
  /// holds anything but a saved map's state files (a save replaces the folder whole) or nothing can be
  /// made there.
  explicit MapSave(std::string directory, uint64_t map_id = newMapId());
  /// Not committed: the staging folder is removed and `directory` is as it was.
  ~MapSave();
  MapSave(const MapSave&) = delete;
  MapSave& operator=(const MapSave&) = delete;

  /// Where the stages write their state files for this save.
  const std::string& staging() const { return staging_; }
  uint64_t mapId() const { return map_id_; }
  /// Puts the staged folder in place of `directory` (exchanged in one rename where the file system can, so
  /// that no moment is without a map) and flushes the names to disk. Throws DataError; `directory` is then
  /// as it was.
  void commit();

 private:
  std::string directory_, staging_;
  uint64_t map_id_;
  bool committed_ = false;
};

/// The map id every one of `stages`' state files in `directory` carries. Throws DataError naming the file
/// that is missing, broken, or of another save than the first. Reads the files' headers only.
uint64_t checkMapFolder(const std::string& directory, const std::vector<std::string>& stages);

/// The error for `path` of map save `id` found where the other files are of save `expected` (`whose`
/// names them, e.g. "the tracking stage's file").
DataError mixedSaveError(const std::string& path, uint64_t id, const std::string& whose, uint64_t expected);

/// "0123456789abcdef": how a map id is shown.
std::string mapIdText(uint64_t map_id);

}  // namespace binloop
