#include "binloop/io/map_folder.h"

#include <fcntl.h>
#include <stdio.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>

#include "binloop/io/data_error.h"
#include "binloop/io/durable_file.h"
#include "binloop/io/filesystem.h"
#include "binloop/io/state_file.h"
#include "binloop/util/hash_random.h"

namespace binloop {
namespace fs = std::filesystem;

uint64_t newMapId() {
  static std::atomic<uint64_t> calls{0};
  const uint64_t now = static_cast<uint64_t>(std::chrono::system_clock::now().time_since_epoch().count());
  const uint64_t id = hashCombine(hashCombine(now, static_cast<uint64_t>(::getpid())), ++calls);
  return id ? id : 1;
}

std::string mapIdText(uint64_t map_id) {
  char s[17];
  std::snprintf(s, sizeof s, "%016llx", static_cast<unsigned long long>(map_id));
  return s;
}

namespace {

std::string withoutTrailingSlash(std::string d) {
  while (d.size() > 1 && d.back() == '/') d.pop_back();
  return d;
}

// What a save may replace: nothing, or a folder of state files (and partial ones an interrupted save left).
void requireReplaceable(const std::string& directory) {
  std::error_code ec;
  if (!fs::exists(directory, ec)) return;
  if (!fs::is_directory(directory, ec)) throw dataError(directory, 0, "is a file, not a map folder");
  for (const auto& e : fs::directory_iterator(directory, ec)) {
    const std::string name = e.path().filename().string();
    const bool state =
        e.is_regular_file() && (e.path().extension() == ".state" || e.path().extension() == ".partial");
    if (!state) {
      throw dataError(directory, 0,
                      "holds '" + name + "', which is not a saved map's: a save replaces the folder " +
                          "whole, so give a new folder (or one that holds only a map)");
    }
  }
  if (ec) throw dataError(directory, 0, "cannot list the folder: " + ec.message());
}

}  // namespace

MapSave::MapSave(std::string directory, uint64_t map_id)
    : directory_(withoutTrailingSlash(std::move(directory))), map_id_(map_id) {
  if (directory_.empty()) throw dataError(directory_, 0, "no map folder given");
  requireReplaceable(directory_);
  staging_ = directory_ + ".saving-" + mapIdText(map_id_);
  std::error_code ec;
  fs::remove_all(staging_, ec);  // a staging folder of this id can only be a leftover
  fs::create_directories(staging_, ec);
  if (ec) throw dataError(staging_, 0, "cannot make the folder to save the map in: " + ec.message());
}

MapSave::~MapSave() {
  if (committed_) return;
  std::error_code ec;
  fs::remove_all(staging_, ec);
}

void MapSave::commit() {
  if (committed_) return;
  syncToDisk(staging_);
  requireReplaceable(directory_);  // still (it may have changed while the stages wrote)
  std::error_code ec;
  if (!fs::exists(directory_, ec)) {
    if (std::rename(staging_.c_str(), directory_.c_str()) != 0)
      throw dataError(directory_, 0, "cannot rename " + staging_ + " to it: " + std::strerror(errno));
  } else if (::renameat2(AT_FDCWD, staging_.c_str(), AT_FDCWD, directory_.c_str(), RENAME_EXCHANGE) != 0) {
    // A file system without the exchange: the old map is moved aside, the new one in, then the old removed.
    const std::string aside = directory_ + ".replaced-" + mapIdText(map_id_);
    fs::remove_all(aside, ec);
    if (std::rename(directory_.c_str(), aside.c_str()) != 0)
      throw dataError(directory_, 0, "cannot move the old map aside: " + std::string(std::strerror(errno)));
    if (std::rename(staging_.c_str(), directory_.c_str()) != 0) {
      const std::string why = std::strerror(errno);
      std::rename(aside.c_str(), directory_.c_str());
      throw dataError(directory_, 0, "cannot rename " + staging_ + " to it: " + why);
    }
    fs::remove_all(aside, ec);
  } else {
    fs::remove_all(staging_, ec);  // now the old map
  }
  committed_ = true;
  const fs::path parent = fs::path(directory_).parent_path();
  syncToDisk(parent.empty() ? "." : parent.string());
}

DataError mixedSaveError(const std::string& path, uint64_t id, const std::string& whose, uint64_t expected) {
  return dataError(path, 0,
                   "belongs to map save " + mapIdText(id) + ", " + whose + " to " + mapIdText(expected) +
                       ": the folder mixes two saves (save the map again)");
}

uint64_t checkMapFolder(const std::string& directory, const std::vector<std::string>& stages) {
  requireDirectory(directory);
  uint64_t first = 0;
  std::string first_stage;
  for (const std::string& stage : stages) {
    const uint64_t id = stateFileMapId(stageStatePath(directory, stage), stage);
    if (first_stage.empty()) {
      first = id;
      first_stage = stage;
    } else if (id != first) {
      throw mixedSaveError(stageStatePath(directory, stage), id, "the " + first_stage + " stage's file",
                           first);
    }
  }
  return first;
}

}  // namespace binloop
