#pragma once
// Where the SLAM's place-recognition models come from: trained model files <dir>/<name>.bin, each checked
// against the extractor settings the SLAM runs with (a vocabulary must see at run time the descriptors it
// was trained on). Shared by the offline runner and the nodelets so that both load models the same way.
#include <memory>
#include <string>
#include <vector>

#include "binloop/features/orb_slam_extractor.h"
#include "binloop/loop/loop_detector.h"
#include "binloop/place/hbow_recognizer.h"
#include "binloop/place/place_recognizer.h"

namespace binloop {

/// Makes <dir>/<name>.bin with `options` (thresholds); the extractor check expects `orb`'s settings and is
/// skipped with a warning when `force`. The factory throws PlaceError as makePlaceRecognizer.
LoopDetector::ModelFactory modelFileFactory(const std::string& dir, const OrbSlamParams& orb, bool force,
                                            RecognizerOptions options = {});

/// The identity (place/model_file.h, modelIdentity) of <dir>/<name>.bin, "" when it cannot be read: what a
/// saved map records and checks of the vocabularies its indices were built with.
std::string modelFileIdentity(const std::string& path);
LoopDetector::ModelIdentity modelFileIdentities(const std::string& dir);

/// The shadow models a user's list names (`run --shadow`, the nodelet's `shadow` parameter): "all" is every
/// model with a file in `dir` but `active` (those without one, e.g. the hbow vocabulary a clone does not
/// ship, go to `skipped`), otherwise a comma list whose names must be models (PlaceError otherwise; a named
/// model without a file fails when it is loaded, with the reason).
std::vector<std::string> shadowModelNames(const std::string& spec, const std::string& active,
                                          const std::string& dir,
                                          std::vector<std::string>* skipped = nullptr);

/// The hbow vocabulary tracking indexes its keyframes with for relocalisation, checked like a model.
/// Throws PlaceError for a missing, corrupt or mismatched file.
std::shared_ptr<const VocabularyTree> loadRelocalisationVocabulary(const std::string& path,
                                                                   const OrbSlamParams& orb, bool force);

}  // namespace binloop
