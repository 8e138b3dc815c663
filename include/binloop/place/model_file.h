#pragma once
// The one binary file format of every place-recognition model (see docs/loop_models.md, "Model files").
//
//   header (fixed 128 bytes): magic "BINLOOPM", format version, model type, descriptor bits, weighting,
//     k, levels, words, training seed, training-data hash, training descriptor and image counts, payload
//     size and payload checksum; version 3 adds the extractor the training descriptors came from and its
//     settings (bytes 88-119; versions 1 and 2 record none: "extractor unknown");
//   payload: tagged sections, each {tag (4 chars), element size, count, bytes}, in the order the model
//     writes them. Version 2 pads so that every section's bytes start at a multiple of 64 in the file.
//
// A file is mapped into memory (mmap), not copied, and checked (size, checksum, section tags and sizes)
// before any model sees it, so a truncated or mismatched file is refused with a message that says what
// was expected and what was found. Because version-2 sections are aligned, a model can use a large
// section where it lies in the mapping (view()) with no copy and no per-element work: that is what lets a
// 1M-word vocabulary load in milliseconds. Version-1 files are still read (their sections are copied).
#include <cstdint>
#include <cstring>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "binloop/features/extractor_settings.h"
#include "binloop/place/place_error.h"
#include "binloop/util/checksum.h"  // checksum64, the version-2 payload checksum (~10x hashBytes)

namespace binloop {

enum class ModelType : uint32_t { kHbow = 1, kFabmap = 2, kVlad = 3, kHmvlad = 4, kVladPq = 5 };
std::string modelTypeName(ModelType t);
/// Throws PlaceError listing the known names.
ModelType modelTypeFromName(const std::string& name);

enum class Weighting : uint32_t { kTfIdf = 0, kTf = 1, kIdf = 2, kBinary = 3 };

struct ModelHeader {
  static constexpr uint32_t kVersion = 3;  // written; versions 1, 2 and 3 are read
  uint32_t version = kVersion;             // of the file read (ModelReader); save() always writes kVersion
  ModelType type = ModelType::kHbow;
  uint32_t descriptor_bits = 256;
  Weighting weighting = Weighting::kTfIdf;
  uint32_t k = 0;
  uint32_t levels = 0;
  uint64_t words = 0;
  uint64_t seed = 0;
  uint64_t training_hash = 0;
  uint64_t training_descriptors = 0;
  uint64_t training_images = 0;
  ExtractorSettings extractor;    // what made the training descriptors (version 3; unknown before)
  uint64_t payload_checksum = 0;  // of the file read (set by readers; the writer computes its own)

  std::string describe() const;
};

/// Reads and checks only the 128-byte header (magic, version, descriptor size): no mapping, no checksum,
/// so a caller can look at a model before loading it. Throws PlaceError as ModelReader does.
ModelHeader readModelHeader(const std::string& path);
/// One line that tells two vocabularies apart (model type, words, training data hash, payload checksum): what
/// a saved map records of the vocabulary its indices were built with.
std::string modelIdentity(const ModelHeader& h);

/// What a caller that loads a model will feed it, so that a model trained on other descriptors is caught
/// at load time instead of silently finding nothing. `expected` unknown = no check.
struct ExtractorCheck {
  ExtractorSettings expected;
  /// A mismatch then warns and the model is loaded anyway (the tools' --force-extractor).
  bool force = false;
  /// How the user forces it, named in the refusal.
  std::string force_hint = "--force-extractor";
  /// Where warnings go (one line each, no "warning:" prefix); empty: std::cerr as "warning: <line>".
  std::function<void(const std::string&)> warn;
  /// The caller describes images at the size they come in and cannot scale them as the model's training
  /// images were (the SLAM: a keyframe's descriptors are tracking's): a model that differs only in that
  /// scaling (ExtractorSettings::max_side) is loaded with a warning instead of refused.
  bool images_as_they_come = false;
};

/// Compares the header's extractor with `c.expected` (nothing when `expected` is unknown):
/// - equal: nothing;
/// - different only in max_side, c.images_as_they_come: warns "<path>: trained on images scaled to a
///   longer side <= N px; these are described at the size they come in";
/// - different, c.force false: throws PlaceError "<path>: trained on descriptors of <its settings>, but
///   they will come from <expected> (differ: <fields>); a vocabulary only fits descriptors like those it
///   was trained on: retrain it with these settings, or use it anyway with <force_hint>";
/// - different, c.force true: warns "<path>: trained on descriptors of <...>, but they will come from
///   <...> (differ: <fields>); used anyway (<force_hint>)";
/// - header records no extractor (file versions 1-2): warns "<path>: the model file (version N) does not
///   record which extractor it was trained with; descriptors will come from <expected> (retrain it if
///   they differ)".
void checkModelExtractor(const std::string& path, const ModelHeader& h, const ExtractorCheck& c);
/// The same, reading the header from `path` first.
void checkModelExtractor(const std::string& path, const ExtractorCheck& c);

/// Collects sections in memory; save() writes header + payload to `path` through a temporary file.
class ModelWriter {
 public:
  explicit ModelWriter(const ModelHeader& h) : header_(h) {}

  template <typename T>
  void section(const char (&tag)[5], const std::vector<T>& v) {
    raw(tag, sizeof(T), v.size(), v.data());
  }
  void raw(const char* tag4, uint32_t elem_size, uint64_t count, const void* data);
  void save(const std::string& path) const;

 private:
  ModelHeader header_;
  std::vector<uint8_t> payload_;
};

/// Elements of a section where they lie (in a mapped file or a buffer that `keep` owns).
template <typename T>
struct SectionView {
  const T* data = nullptr;
  size_t size = 0;
  const T& operator[](size_t i) const { return data[i]; }
  const T* begin() const { return data; }
  const T* end() const { return data + size; }
  bool empty() const { return size == 0; }
};

class ModelReader {
 public:
  /// Reads and checks the whole file. Throws PlaceError ("<path>: ...") on a missing, short,
  /// corrupt or future-version file.
  explicit ModelReader(const std::string& path);

  const ModelHeader& header() const { return header_; }
  const std::string& path() const { return path_; }
  /// Throws when the file holds another model type.
  void expectType(ModelType t) const;

  /// Next section; throws when its tag or element size differ from what the model expects.
  template <typename T>
  std::vector<T> section(const char (&tag)[5]) {
    uint64_t count = 0;
    const uint8_t* p = next(tag, sizeof(T), &count);
    std::vector<T> v(count);
    if (count) std::memcpy(v.data(), p, count * sizeof(T));
    return v;
  }
  /// Next section without copying it: valid as long as storage() is held. Sections of a version-1 file
  /// that are not aligned for T are copied into a buffer that storage() also holds.
  template <typename T>
  SectionView<T> view(const char (&tag)[5]) {
    uint64_t count = 0;
    const uint8_t* p = next(tag, sizeof(T), &count);
    if (reinterpret_cast<uintptr_t>(p) % alignof(T) != 0) p = copied(p, count * sizeof(T));
    return {reinterpret_cast<const T*>(p), count};
  }
  /// Keeps the mapped file (and any copied sections) alive for views.
  std::shared_ptr<const void> storage() const { return storage_; }
  /// Throws if sections remain unread (a file written by a different model layout).
  void expectEnd() const;

 private:
  const uint8_t* next(const char* tag4, uint32_t elem_size, uint64_t* count);
  const uint8_t* copied(const uint8_t* p, size_t bytes);
  struct Storage;
  std::string path_;
  ModelHeader header_;
  uint32_t version_ = 0;
  std::shared_ptr<Storage> storage_;
  const uint8_t* file_ = nullptr;   // the mapped file, header included
  size_t file_size_ = 0, pos_ = 0;  // pos_: offset of the next section header in the file
};

/// A 64-bit hash for training-data fingerprints and version-1 payload checksums (one word at a time).
uint64_t hashBytes(const void* data, size_t n, uint64_t seed = 0);

}  // namespace binloop
