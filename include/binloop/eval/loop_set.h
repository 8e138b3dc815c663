#pragma once
// Real-image loop sets: an image sequence that visits places and comes back to them, made from real
// photographs so that loop ranking can be tuned and checked on real image statistics (docs/loop_models.md,
// "Real-image loop sets").
//
// A list file names one place per line: `<name> <image A> [<image B> | -]`. Each place is first visited
// as three crops of A panning left to right (a camera sweeping a room). Places with a B are revisited
// later, in a seeded shuffled order, as two crops of B: B is a real second view (another photo of the same
// scene: stereo partner, later frame, other viewpoint or lighting), or, when B is `=`, A itself seen again
// through a seeded random homography with a change of light, blur and noise. `-` means the place is never
// revisited (a distractor). The ground truth pairs a revisit frame with each first-visit frame of its place
// whose window covers at least half the same width of the source image (all three for 4:3 photos).
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace binloop {

struct LoopSetPlace {
  std::string name, first, second;  // second: a path, "=" (synthetic second view) or "" (no revisit)
};

/// Reads a list file; `$SHARED` in a path stands for `shared_dir`. Throws DataError with file:line on a
/// malformed line or an image that does not exist.
std::vector<LoopSetPlace> readLoopSetList(const std::string& path, const std::string& shared_dir);

struct LoopSetFrame {
  std::string place, source;  // source image and how it was viewed ("A crop 2", "B warped crop 1")
  bool revisit = false;
};

struct LoopSet {
  std::vector<LoopSetFrame> frames;
  std::vector<std::pair<int, int>> loops;  // (query, ref) frame indices, query > ref
};

/// Writes the frames as `<out>/NNNNNN.png` (640x480 gray) and returns what they are. Throws DataError on
/// an unreadable image; the same list and seed give the same bytes.
LoopSet makeLoopSet(const std::vector<LoopSetPlace>& places, const std::string& out_dir, uint64_t seed);

}  // namespace binloop
