#pragma once
// Where the package's shipped files (vocab/, config/) are, found from any working folder: the tools'
// defaults and the nodelets' default parameters point here, not at paths relative to wherever the user
// stands.
#include <string>

namespace binloop {

/// The shipped files, relative to packageDir(): the detectors' models (<dir>/<model>.bin) and the small hbow
/// vocabulary that relocalisation uses by default (k=8, L=5: small enough to track; the k=10, L=6 hbow.bin
/// is made by vocab/make_vocab.sh). Two sets, one per BRIEF test pattern, since a model only answers
/// descriptors made with the tests it was trained on: vocab/kitti08 (binloop's Gaussian tests, rendered
/// KITTI route 08) and vocab/photos (ORB's learned tests, real photos).
inline constexpr const char* kShippedModelDir = "vocab/kitti08";
inline constexpr const char* kRelocVocab = "vocab/kitti08/hbow_k8l5.bin";
inline constexpr const char* kPhotoModelDir = "vocab/photos";
inline constexpr const char* kPhotoRelocVocab = "vocab/photos/hbow_k8l5.bin";

/// What a model-folder or relocalisation-vocabulary setting holds by default: "auto", the shipped set made
/// with the BRIEF tests in use (so that turning on orb.learned_pattern needs no second setting).
inline constexpr const char* kAutoVocab = "auto";
/// `given` itself, or for "auto" the shipped model folder (absolute) for the tests in use.
std::string modelDirFor(const std::string& given, bool orb_learned_tests);
/// `given` itself, or for "auto" the shipped relocalisation vocabulary (absolute) for the tests in use.
std::string relocVocabFor(const std::string& given, bool orb_learned_tests);

/// The first of: $BINLOOP_PACKAGE_DIR; the install space's share/binloop beside this library
/// (<prefix>/lib/libbinloop_core.so -> <prefix>/share/binloop) or beside the running program
/// (<prefix>/lib/binloop/<tool>); the source folder the library was built from. An install-space candidate
/// counts when it holds vocab/.
std::string packageDir();
/// packageDir() + "/" + rel.
std::string packagePath(const std::string& rel);

}  // namespace binloop
