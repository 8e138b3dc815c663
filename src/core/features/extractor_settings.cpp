#include "binloop/features/extractor_settings.h"

#include <sstream>

namespace binloop {

bool ExtractorSettings::operator==(const ExtractorSettings& o) const {
  return kind == o.kind && features == o.features && scale_factor == o.scale_factor && levels == o.levels &&
         ini_fast == o.ini_fast && min_fast == o.min_fast && cell_px == o.cell_px && max_side == o.max_side;
}

namespace {

std::string kindName(ExtractorKind k) {
  switch (k) {
    case ExtractorKind::kUnknown:
      return "unknown";
    case ExtractorKind::kBinloopOrb:
      return "binloop ORB with the Gaussian BRIEF pattern";
    case ExtractorKind::kBinloopOrbRbrief:
      return "binloop ORB with ORB's learned pattern";
    case ExtractorKind::kDbow2Import:
      return "imported DBoW2";
  }
  return "kind " + std::to_string(static_cast<uint32_t>(k));
}

std::string sideName(uint32_t max_side) { return max_side ? std::to_string(max_side) : "none"; }

}  // namespace

std::string ExtractorSettings::describe() const {
  std::ostringstream s;
  switch (kind) {
    case ExtractorKind::kUnknown:
      return "an unknown extractor (not recorded)";
    case ExtractorKind::kDbow2Import:
      return "the ORB of an imported DBoW2 vocabulary (ORB-SLAM2's or OpenCV's pattern, settings not "
             "recorded)";
    case ExtractorKind::kBinloopOrb:
    case ExtractorKind::kBinloopOrbRbrief:
      s << kindName(kind) << " (" << features << " features, scale " << scale_factor << ", " << levels
        << " levels, FAST " << ini_fast << "/" << min_fast << ", " << cell_px << "-px cells, "
        << (max_side ? "images scaled to a longer side <= " + std::to_string(max_side) + " px"
                     : "full-size images")
        << ")";
      return s.str();
  }
  return "extractor kind " + std::to_string(static_cast<uint32_t>(kind));
}

std::string ExtractorSettings::differences(const ExtractorSettings& o) const {
  std::ostringstream s;
  if (kind != o.kind) {
    s << "extractor " << kindName(kind) << " vs " << kindName(o.kind);
    // Two binloop extractors differ in their BRIEF tests; say what else differs too.
    const auto binloop = [](ExtractorKind k) {
      return k == ExtractorKind::kBinloopOrb || k == ExtractorKind::kBinloopOrbRbrief;
    };
    if (!binloop(kind) || !binloop(o.kind)) return s.str();
  }
  auto field = [&](const char* name, const auto& a, const auto& b) {
    if (a == b) return;
    s << (s.tellp() > 0 ? ", " : "") << name << " " << a << " vs " << b;
  };
  field("features", features, o.features);
  field("scale factor", scale_factor, o.scale_factor);
  field("levels", levels, o.levels);
  field("ini FAST", ini_fast, o.ini_fast);
  field("min FAST", min_fast, o.min_fast);
  field("cell px", cell_px, o.cell_px);
  field("max side", sideName(max_side), sideName(o.max_side));
  return s.str();
}

}  // namespace binloop
