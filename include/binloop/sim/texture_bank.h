#pragma once
// The textures a synthetic world is painted with: façades cut from real photographs (with window grids
// laid over them so they read as buildings), ground materials, car bodies, bark and foliage. Built
// deterministically from (photo files, seed); with no photos, a procedural fallback.
#include <string>
#include <vector>

#include "binloop/sim/texture.h"

namespace binloop::sim {

struct TextureBank {
  std::vector<Texture> textures;  // every texture; the indices below point into it
  std::vector<int> facades;       // building fronts
  std::vector<int> walls;         // building sides, fences (no windows)
  std::vector<int> cars;
  int road = -1, pavement = -1, grass = -1, pole = -1, foliage = -1;
  size_t photos_used = 0;  // 0: procedural fallback only

  /// `photos`: image files (any format OpenCV reads; unreadable ones are skipped and counted out).
  static TextureBank build(const std::vector<std::string>& photos, uint64_t seed, int n_facades = 48);
};

/// Real photographs that Debian packages installed by scripts/setup.sh put on the machine (opencv-doc,
/// python3-skimage), in a fixed order; only those that exist are returned.
std::vector<std::string> defaultTexturePhotos();

}  // namespace binloop::sim
