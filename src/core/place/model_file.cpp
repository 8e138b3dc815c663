#include "binloop/place/model_file.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <sstream>

#include "binloop/util/hash_random.h"

namespace binloop {

namespace {

constexpr char kMagic[8] = {'B', 'I', 'N', 'L', 'O', 'O', 'P', 'M'};
constexpr size_t kHeaderBytes = 128;

// Fixed little-endian layout of the header; offsets documented by the order of put() calls.
struct HeaderCodec {
  uint8_t bytes[kHeaderBytes] = {};
  size_t pos = 0;
  template <typename T>
  void put(T v) {
    std::memcpy(bytes + pos, &v, sizeof(T));
    pos += sizeof(T);
  }
  template <typename T>
  T get() {
    T v;
    std::memcpy(&v, bytes + pos, sizeof(T));
    pos += sizeof(T);
    return v;
  }
};

const char* const kTypeNames[] = {"", "hbow", "fabmap", "vlad", "hmvlad", "vladpq"};

}  // namespace

std::string modelTypeName(ModelType t) {
  const auto i = static_cast<uint32_t>(t);
  return i >= 1 && i <= 5 ? kTypeNames[i] : "unknown(" + std::to_string(i) + ")";
}

ModelType modelTypeFromName(const std::string& name) {
  for (uint32_t i = 1; i <= 5; ++i)
    if (name == kTypeNames[i]) return static_cast<ModelType>(i);
  throw PlaceError("unknown model '" + name + "' (known: hbow, fabmap, vlad, hmvlad, vladpq)");
}

std::string ModelHeader::describe() const {
  std::ostringstream s;
  s << modelTypeName(type) << " model, " << descriptor_bits << "-bit descriptors, k=" << k << " levels=" << levels
    << " words=" << words << ", trained with seed " << seed << " on " << training_descriptors << " descriptors of "
    << training_images << " images (data hash " << std::hex << training_hash << ")";
  return s.str();
}

uint64_t hashBytes(const void* data, size_t n, uint64_t seed) {
  const auto* p = static_cast<const uint8_t*>(data);
  uint64_t h = splitmix64(seed ^ n);
  size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    uint64_t w;
    std::memcpy(&w, p + i, 8);
    h = (h ^ w) * 0x100000001B3ull + (h >> 29);
  }
  uint64_t tail = 0;
  std::memcpy(&tail, p + i, n - i);
  return splitmix64(h ^ tail);
}

void ModelWriter::raw(const char* tag4, uint32_t elem_size, uint64_t count, const void* data) {
  const size_t at = payload_.size();
  const uint64_t bytes = elem_size * count;
  payload_.resize(at + 16 + bytes);
  std::memcpy(&payload_[at], tag4, 4);
  std::memcpy(&payload_[at + 4], &elem_size, 4);
  std::memcpy(&payload_[at + 8], &count, 8);
  if (bytes) std::memcpy(&payload_[at + 16], data, bytes);
}

void ModelWriter::save(const std::string& path) const {
  HeaderCodec c;
  for (char m : kMagic) c.put(m);
  c.put(ModelHeader::kVersion);
  c.put(static_cast<uint32_t>(header_.type));
  c.put(header_.descriptor_bits);
  c.put(static_cast<uint32_t>(header_.weighting));
  c.put(header_.k);
  c.put(header_.levels);
  c.put(header_.words);
  c.put(header_.seed);
  c.put(header_.training_hash);
  c.put(header_.training_descriptors);
  c.put(header_.training_images);
  c.put(static_cast<uint64_t>(payload_.size()));
  c.put(hashBytes(payload_.data(), payload_.size()));
  const std::string tmp = path + ".partial";
  std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(tmp.c_str(), "wb"), &std::fclose);
  if (!f) throw PlaceError(path + ": cannot write");
  if (std::fwrite(c.bytes, 1, kHeaderBytes, f.get()) != kHeaderBytes ||
      std::fwrite(payload_.data(), 1, payload_.size(), f.get()) != payload_.size())
    throw PlaceError(path + ": write failed (disk full?)");
  f.reset();
  std::filesystem::rename(tmp, path);
}

ModelReader::ModelReader(const std::string& path) : path_(path) {
  std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) throw PlaceError(path + ": cannot open model file");
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) throw PlaceError(path + ": cannot open model file");
  HeaderCodec c;
  const size_t got = std::fread(c.bytes, 1, kHeaderBytes, f.get());
  if (std::memcmp(c.bytes, kMagic, std::min<size_t>(got, 8)) != 0 || got == 0)
    throw PlaceError(path + ": not a binloop model file (bad magic; DBoW2 vocabularies are converted with "
                            "'binloop train hbow --import <file>')");
  if (size < kHeaderBytes || got != kHeaderBytes)
    throw PlaceError(path + ": truncated model file (" + std::to_string(size) + " bytes, the header alone is 128)");
  c.pos = 8;
  const auto version = c.get<uint32_t>();
  if (version != ModelHeader::kVersion)
    throw PlaceError(path + ": model file version " + std::to_string(version) + ", this build reads version " +
                     std::to_string(ModelHeader::kVersion));
  header_.type = static_cast<ModelType>(c.get<uint32_t>());
  header_.descriptor_bits = c.get<uint32_t>();
  header_.weighting = static_cast<Weighting>(c.get<uint32_t>());
  header_.k = c.get<uint32_t>();
  header_.levels = c.get<uint32_t>();
  header_.words = c.get<uint64_t>();
  header_.seed = c.get<uint64_t>();
  header_.training_hash = c.get<uint64_t>();
  header_.training_descriptors = c.get<uint64_t>();
  header_.training_images = c.get<uint64_t>();
  const auto payload = c.get<uint64_t>();
  const auto checksum = c.get<uint64_t>();
  if (size != kHeaderBytes + payload)
    throw PlaceError(path + ": truncated model file: header promises " + std::to_string(kHeaderBytes + payload) +
                     " bytes, file has " + std::to_string(size));
  payload_.resize(payload);
  if (std::fread(payload_.data(), 1, payload, f.get()) != payload) throw PlaceError(path + ": read failed");
  if (hashBytes(payload_.data(), payload_.size()) != checksum)
    throw PlaceError(path + ": corrupt model file (payload checksum differs)");
  if (header_.descriptor_bits != 256)
    throw PlaceError(path + ": vocabulary of " + std::to_string(header_.descriptor_bits) +
                     "-bit descriptors; binloop uses 256-bit ORB descriptors");
}

void ModelReader::expectType(ModelType t) const {
  if (header_.type != t)
    throw PlaceError(path_ + ": holds a " + modelTypeName(header_.type) + " model, expected " + modelTypeName(t));
}

const uint8_t* ModelReader::next(const char* tag4, uint32_t elem_size, uint64_t* count) {
  const std::string want(tag4, 4);
  if (pos_ + 16 > payload_.size()) throw PlaceError(path_ + ": section '" + want + "' missing (file ends)");
  const std::string tag(reinterpret_cast<const char*>(&payload_[pos_]), 4);
  uint32_t es;
  std::memcpy(&es, &payload_[pos_ + 4], 4);
  std::memcpy(count, &payload_[pos_ + 8], 8);
  if (tag != want) throw PlaceError(path_ + ": expected section '" + want + "', found '" + tag + "'");
  if (es != elem_size)
    throw PlaceError(path_ + ": section '" + want + "' has " + std::to_string(es) + "-byte elements, expected " +
                     std::to_string(elem_size));
  const uint64_t bytes = es * *count;
  if (pos_ + 16 + bytes > payload_.size()) throw PlaceError(path_ + ": section '" + want + "' runs past the end");
  const uint8_t* p = &payload_[pos_ + 16];
  pos_ += 16 + bytes;
  return p;
}

void ModelReader::expectEnd() const {
  if (pos_ != payload_.size())
    throw PlaceError(path_ + ": " + std::to_string(payload_.size() - pos_) + " bytes of unread sections");
}

}  // namespace binloop
