#pragma once
// ORB descriptors of many images at once, for training and evaluation: the images of a folder (a KITTI
// sequence's image_0/, or any folder of png/jpg in natural order), extracted on several threads with the
// result in image order whatever the thread timing. The extractor is the SLAM's (OrbSlamExtractor), with
// the SLAM's settings unless told otherwise, so that a vocabulary trained here sees at run time the
// descriptors it was trained on.
#include <string>
#include <vector>

#include "binloop/features/orb_slam_extractor.h"
#include "binloop/types/binary_descriptor.h"
#include "binloop/util/progress_bar.h"

namespace binloop {

/// `dir`/image_0 when it exists (a KITTI-layout sequence), else the png/jpg files of `dir` in natural
/// order (2.jpg before 10.jpg). Throws DataError when there are none.
std::vector<std::string> listImages(const std::string& dir);

struct ExtractOptions {
  OrbSlamParams orb;  // defaults = the SLAM's (config/kitti.yaml, orb:)
  int max_side =
      0;  // > 0: larger images are scaled down (area interpolation) so that their longer side is this
  int threads = 2;
  /// Unreadable images (corrupt, 16-bit) give an empty set and a line in `skipped` instead of an error.
  bool skip_unreadable = false;
  std::vector<std::string>* skipped = nullptr;
};

/// What a model trained on (or fed with) these descriptors records: extractorSettings(o.orb, o.max_side).
ExtractorSettings extractorSettings(const ExtractOptions& o);

/// Throws DataError naming the first unreadable image, FeatureError for extractor settings out of range.
std::vector<Descriptors> extractDescriptors(const std::vector<std::string>& paths, const ExtractOptions& o,
                                            const ProgressFn& progress = {});

}  // namespace binloop
