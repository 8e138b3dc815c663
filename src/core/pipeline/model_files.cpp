#include "binloop/pipeline/model_files.h"

#include <algorithm>
#include <filesystem>
#include <sstream>

#include "binloop/place/model_file.h"

namespace binloop {

LoopDetector::ModelFactory modelFileFactory(const std::string& dir, const OrbSlamParams& orb, bool force,
                                            RecognizerOptions options) {
  options.extractor.expected = extractorSettings(orb, 0);
  options.extractor.force = force;
  options.extractor.images_as_they_come = true;
  return [dir, options](const std::string& name) {
    RecognizerOptions ro = options;
    ro.model_file = (std::filesystem::path(dir) / (name + ".bin")).string();
    // The one model the package cannot ship: say how to make it rather than only that it is missing.
    if (name == "hbow" && !std::filesystem::exists(ro.model_file)) {
      throw PlaceError(
          ro.model_file +
          ": not found: the k=10, L=6 hbow vocabulary (26 MB) is not shipped; "
          "vocab/make_vocab.sh hbow makes it (about 6 minutes, from KITTI route 08's poses), or use a "
          "shipped model (hmvlad, vlad, vladpq, fabmap)");
    }
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

std::vector<std::string> shadowModelNames(const std::string& spec, const std::string& active,
                                          const std::string& dir, std::vector<std::string>* skipped) {
  const std::vector<std::string>& known = placeModelNames();
  std::vector<std::string> out;
  if (spec == "all") {
    for (const std::string& n : known) {
      if (n == active) continue;
      if (std::filesystem::exists(std::filesystem::path(dir) / (n + ".bin"))) {
        out.push_back(n);
      } else if (skipped) {
        skipped->push_back(n);
      }
    }
    return out;
  }
  std::stringstream ss(spec);
  for (std::string n; std::getline(ss, n, ',');) {
    if (n.empty()) continue;
    if (std::find(known.begin(), known.end(), n) == known.end())
      throw PlaceError("shadow model '" + n + "': not one of hbow, fabmap, vlad, hmvlad, vladpq");
    out.push_back(n);
  }
  return out;
}

std::shared_ptr<const VocabularyTree> loadRelocalisationVocabulary(const std::string& path,
                                                                   const OrbSlamParams& orb, bool force) {
  ExtractorCheck check;
  check.expected = extractorSettings(orb, 0);
  check.force = force;
  check.images_as_they_come = true;
  checkModelExtractor(path, check);
  return HbowRecognizer::loadVocabulary(path);
}

}  // namespace binloop
