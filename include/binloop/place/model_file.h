#pragma once
// The one binary file format of every place-recognition model (see README, "Model files").
//
//   header (fixed 128 bytes): magic "BINLOOPM", format version, model type, descriptor bits, weighting,
//     k, levels, words, training seed, training-data hash, training descriptor and image counts, payload
//     size and payload checksum;
//   payload: tagged sections, each {tag (4 chars), element size, count, bytes}, in the order the model
//     writes them.
//
// A file is read with one read() into memory and checked (size, checksum, section tags and sizes)
// before any model sees it, so a truncated or mismatched file is refused with a message that says what
// was expected and what was found.
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "binloop/place/place_error.h"

namespace binloop {

enum class ModelType : uint32_t { kHbow = 1, kFabmap = 2, kVlad = 3, kHmvlad = 4, kVladPq = 5 };
std::string modelTypeName(ModelType t);
/// Throws PlaceError listing the known names.
ModelType modelTypeFromName(const std::string& name);

enum class Weighting : uint32_t { kTfIdf = 0, kTf = 1, kIdf = 2, kBinary = 3 };

struct ModelHeader {
  static constexpr uint32_t kVersion = 1;
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

  std::string describe() const;
};

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
  /// Throws if sections remain unread (a file written by a different model layout).
  void expectEnd() const;

 private:
  const uint8_t* next(const char* tag4, uint32_t elem_size, uint64_t* count);
  std::string path_;
  ModelHeader header_;
  std::vector<uint8_t> payload_;
  size_t pos_ = 0;
};

/// A 64-bit hash for training-data fingerprints and payload checksums (word-wise, fast).
uint64_t hashBytes(const void* data, size_t n, uint64_t seed = 0);

}  // namespace binloop
