#include "binloop/pipeline/model_files.h"

#include <filesystem>

#include "binloop/place/model_file.h"

namespace binloop {

LoopDetector::ModelFactory modelFileFactory(const std::string& dir, const OrbSlamParams& orb, bool force,
                                            RecognizerOptions options) {
  options.extractor.expected = extractorSettings(orb, 0);
  options.extractor.force = force;
  return [dir, options](const std::string& name) {
    RecognizerOptions ro = options;
    ro.model_file = (std::filesystem::path(dir) / (name + ".bin")).string();
    // The one model the package cannot ship: say how to make it rather than only that it is missing.
    if (name == "hbow" && !std::filesystem::exists(ro.model_file))
      throw PlaceError(ro.model_file + ": not found: the k=10, L=6 hbow vocabulary (26 MB) is not shipped; "
                       "vocab/make_vocab.sh hbow makes it (about 6 minutes, from KITTI route 08's poses), or use a "
                       "shipped model (hmvlad, vlad, vladpq, fabmap)");
    return makePlaceRecognizer(name, ro);
  };
}

std::string modelFileIdentity(const std::string& path) {
  try {
    return modelIdentity(readModelHeader(path));
  } catch (const PlaceError&) {
    return "";
  }
}

LoopDetector::ModelIdentity modelFileIdentities(const std::string& dir) {
  return [dir](const std::string& name) {
    return modelFileIdentity((std::filesystem::path(dir) / (name + ".bin")).string());
  };
}

std::shared_ptr<const VocabularyTree> loadRelocalisationVocabulary(const std::string& path, const OrbSlamParams& orb,
                                                                   bool force) {
  ExtractorCheck check;
  check.expected = extractorSettings(orb, 0);
  check.force = force;
  checkModelExtractor(path, check);
  return HbowRecognizer::loadVocabulary(path);
}

}  // namespace binloop
