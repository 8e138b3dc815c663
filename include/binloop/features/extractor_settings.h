#pragma once
// Which extractor made a set of descriptors, with its settings: what a model file records of the descriptors
// it was trained on (place/model_file.h), so that a vocabulary is only fed descriptors like those.
#include <cstdint>
#include <string>

namespace binloop {

/// Which extractor made the descriptors a model was trained on. A vocabulary only works on descriptors like
/// those it was trained on: another BRIEF pattern gives unrelated bits, and other settings (feature count,
/// pyramid, image size) other statistics.
enum class ExtractorKind : uint32_t {
  kUnknown = 0,  // not recorded: model files of versions 1-2, or trained from descriptors of unknown origin
  kBinloopOrb =
      1,  // binloop's extractor (features/orb_slam_extractor.h), Gaussian BRIEF tests: the SLAM's default
  kDbow2Import = 2,  // an imported DBoW2 vocabulary (ORB-SLAM2's or OpenCV's ORB pattern; settings not known)
  kBinloopOrbRbrief = 3,  // binloop's extractor with ORB's learned rBRIEF pattern (orb.learned_pattern: 1)
};

/// The extractor and its settings, as the model header records them (kBinloopOrb and kBinloopOrbRbrief: every
/// field; otherwise only `kind`). features/orb_slam_extractor.h makes one from OrbSlamParams
/// (extractorSettings()).
struct ExtractorSettings {
  ExtractorKind kind = ExtractorKind::kUnknown;
  uint32_t features = 0;
  float scale_factor = 0;
  uint32_t levels = 0;
  uint32_t ini_fast = 0;
  uint32_t min_fast = 0;
  uint32_t cell_px = 0;
  uint32_t max_side = 0;  // images were scaled down to this longer side first; 0 = never (full size)

  bool known() const { return kind != ExtractorKind::kUnknown; }
  bool operator==(const ExtractorSettings& o) const;
  bool operator!=(const ExtractorSettings& o) const { return !(*this == o); }
  /// One line, e.g. "binloop ORB with the Gaussian BRIEF pattern (2000 features, scale 1.2, 8 levels, FAST
  /// 20/7, 30-px cells, full-size images)".
  std::string describe() const;
  /// The fields that differ from `o`, e.g. "features 1000 vs 2000, max side 1024 vs none"; "" when equal.
  std::string differences(const ExtractorSettings& o) const;
};

}  // namespace binloop
