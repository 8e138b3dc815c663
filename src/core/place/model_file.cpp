#include "binloop/place/model_file.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <sstream>
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "binloop/util/hash_random.h"

namespace binloop {

namespace {

constexpr char kMagic[8] = {'B', 'I', 'N', 'L', 'O', 'O', 'P', 'M'};
constexpr size_t kHeaderBytes = 128;
constexpr size_t kSectionAlign = 64;  // version 2: section bytes start at a multiple of this in the file

size_t alignUp(size_t x, size_t a) { return (x + a - 1) / a * a; }

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
  if (n > i) std::memcpy(&tail, p + i, n - i);
  return splitmix64(h ^ tail);
}

uint64_t checksum64(const void* data, size_t n) {
  // xxHash64's round on four lanes (our code, its constants): the lanes do not wait for each other.
  constexpr uint64_t kP1 = 0x9E3779B185EBCA87ull, kP2 = 0xC2B2AE3D27D4EB4Full;
  const auto rotl = [](uint64_t x, int r) { return (x << r) | (x >> (64 - r)); };
  const auto* p = static_cast<const uint8_t*>(data);
  uint64_t lane[4] = {kP1 + kP2, kP2, 0, 0 - kP1};
  size_t i = 0;
  for (; i + 32 <= n; i += 32)
    for (int l = 0; l < 4; ++l) {
      uint64_t w;
      std::memcpy(&w, p + i + 8 * l, 8);
      lane[l] = rotl(lane[l] + w * kP2, 31) * kP1;
    }
  uint64_t h = n;
  for (int l = 0; l < 4; ++l) h = splitmix64(h ^ lane[l]);
  uint64_t tail[4] = {0, 0, 0, 0};
  if (n > i) std::memcpy(tail, p + i, n - i);  // an empty section may have no pointer at all
  for (uint64_t t : tail) h = splitmix64(h ^ t);
  return h;
}

void ModelWriter::raw(const char* tag4, uint32_t elem_size, uint64_t count, const void* data) {
  const size_t at = payload_.size();
  const uint64_t bytes = elem_size * count;
  // The header is 128 bytes, so aligning within the payload aligns within the file.
  const size_t data_at = alignUp(at + 16, kSectionAlign);
  payload_.resize(data_at + bytes);
  std::memcpy(&payload_[at], tag4, 4);
  std::memcpy(&payload_[at + 4], &elem_size, 4);
  std::memcpy(&payload_[at + 8], &count, 8);
  if (bytes) std::memcpy(&payload_[data_at], data, bytes);
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
  c.put(checksum64(payload_.data(), payload_.size()));
  const std::string tmp = path + ".partial";
  std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(tmp.c_str(), "wb"), &std::fclose);
  if (!f) throw PlaceError(path + ": cannot write");
  if (std::fwrite(c.bytes, 1, kHeaderBytes, f.get()) != kHeaderBytes ||
      (!payload_.empty() && std::fwrite(payload_.data(), 1, payload_.size(), f.get()) != payload_.size()))
    throw PlaceError(path + ": write failed (disk full?)");
  f.reset();
  std::filesystem::rename(tmp, path);
}

struct ModelReader::Storage {
  void* map = MAP_FAILED;
  size_t size = 0;
  std::vector<std::unique_ptr<uint64_t[]>> copies;
  ~Storage() {
    if (map != MAP_FAILED) munmap(map, size);
  }
};

ModelReader::ModelReader(const std::string& path) : path_(path), storage_(std::make_shared<Storage>()) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  struct stat st {};
  if (fd < 0 || ::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    if (fd >= 0) ::close(fd);
    throw PlaceError(path + ": cannot open model file");
  }
  const auto size = static_cast<size_t>(st.st_size);
  if (size > 0) {
    // MAP_POPULATE maps every page now (they are in the page cache after the first load), so neither
    // the checksum nor the first query pays a page fault per 4 kB.
    storage_->map = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0);
    storage_->size = size;
  }
  ::close(fd);
  if (size > 0 && storage_->map == MAP_FAILED) throw PlaceError(path + ": cannot map model file into memory");
  file_ = static_cast<const uint8_t*>(storage_->map);
  file_size_ = size;
  if (size == 0 || std::memcmp(file_, kMagic, std::min<size_t>(size, 8)) != 0)
    throw PlaceError(path + ": not a binloop model file (bad magic; DBoW2 vocabularies are converted with "
                            "'binloop train hbow --import <file>')");
  if (size < kHeaderBytes)
    throw PlaceError(path + ": truncated model file (" + std::to_string(size) + " bytes, the header alone is 128)");
  HeaderCodec c;
  std::memcpy(c.bytes, file_, kHeaderBytes);
  c.pos = 8;
  version_ = c.get<uint32_t>();
  if (version_ != 1 && version_ != 2)
    throw PlaceError(path + ": model file version " + std::to_string(version_) + ", this build reads versions 1 and " +
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
  const uint64_t computed =
      version_ == 1 ? hashBytes(file_ + kHeaderBytes, payload) : checksum64(file_ + kHeaderBytes, payload);
  if (computed != checksum) throw PlaceError(path + ": corrupt model file (payload checksum differs)");
  if (header_.descriptor_bits != 256)
    throw PlaceError(path + ": vocabulary of " + std::to_string(header_.descriptor_bits) +
                     "-bit descriptors; binloop uses 256-bit ORB descriptors");
  pos_ = kHeaderBytes;
}

void ModelReader::expectType(ModelType t) const {
  if (header_.type != t)
    throw PlaceError(path_ + ": holds a " + modelTypeName(header_.type) + " model, expected " + modelTypeName(t));
}

const uint8_t* ModelReader::next(const char* tag4, uint32_t elem_size, uint64_t* count) {
  const std::string want(tag4, 4);
  if (pos_ + 16 > file_size_) throw PlaceError(path_ + ": section '" + want + "' missing (file ends)");
  const std::string tag(reinterpret_cast<const char*>(file_ + pos_), 4);
  uint32_t es;
  std::memcpy(&es, file_ + pos_ + 4, 4);
  std::memcpy(count, file_ + pos_ + 8, 8);
  if (tag != want) throw PlaceError(path_ + ": expected section '" + want + "', found '" + tag + "'");
  if (es != elem_size)
    throw PlaceError(path_ + ": section '" + want + "' has " + std::to_string(es) + "-byte elements, expected " +
                     std::to_string(elem_size));
  const size_t data_at = version_ == 1 ? pos_ + 16 : alignUp(pos_ + 16, kSectionAlign);
  const uint64_t bytes = es * *count;
  if (*count > file_size_ || data_at + bytes > file_size_)
    throw PlaceError(path_ + ": section '" + want + "' runs past the end");
  pos_ = data_at + bytes;
  return file_ + data_at;
}

const uint8_t* ModelReader::copied(const uint8_t* p, size_t bytes) {
  storage_->copies.emplace_back(new uint64_t[(bytes + 7) / 8]);
  std::memcpy(storage_->copies.back().get(), p, bytes);
  return reinterpret_cast<const uint8_t*>(storage_->copies.back().get());
}

void ModelReader::expectEnd() const {
  if (pos_ != file_size_)
    throw PlaceError(path_ + ": " + std::to_string(file_size_ - pos_) + " bytes of unread sections");
}

}  // namespace binloop
