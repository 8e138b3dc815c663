#pragma once
// Files that survive a crash or a power cut as either the old or the new version: written beside their
// place, flushed to the disk (fsync), renamed over it, and the folder flushed so that the rename itself is
// on the disk. Used by the map's state files and the map folder (map_folder.h).
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace binloop {

/// Writes the pieces, in order, to <path>.partial, syncs it, renames it to `path` and syncs the folder.
/// Throws DataError (folder not writable, disk full); the partial file is removed then.
void writeDurably(const std::string& path, const std::vector<std::pair<const uint8_t*, size_t>>& pieces);

/// fsync of a file or a folder (for a folder: the names in it). Throws DataError.
void syncToDisk(const std::string& path);

}  // namespace binloop
