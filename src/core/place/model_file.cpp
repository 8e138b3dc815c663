#include "binloop/place/model_file.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>

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

// The header fields of the first `size` bytes of a file (size < 128: only enough to report the fault).
// Throws for a bad magic, a short file or an unknown version.
ModelHeader decodeHeader(const std::string& path, const uint8_t* file, size_t size, uint64_t* payload,
                         uint64_t* checksum) {
  if (size == 0 || std::memcmp(file, kMagic, std::min<size_t>(size, 8)) != 0) {
    throw PlaceError(path +
                     ": not a binloop model file (bad magic; DBoW2 vocabularies are converted with "
                     "'binloop train hbow --import <file>')");
  }
  if (size < kHeaderBytes) {
    throw PlaceError(path + ": truncated model file (" + std::to_string(size) +
                     " bytes, the header alone is 128)");
  }
  HeaderCodec c;
  std::memcpy(c.bytes, file, kHeaderBytes);
  c.pos = 8;
  ModelHeader h;
  h.version = c.get<uint32_t>();
  if (h.version < 1 || h.version > ModelHeader::kVersion) {
    throw PlaceError(path + ": model file version " + std::to_string(h.version) +
                     ", this build reads versions 1 to " + std::to_string(ModelHeader::kVersion));
  }
  h.type = static_cast<ModelType>(c.get<uint32_t>());
  h.descriptor_bits = c.get<uint32_t>();
  h.weighting = static_cast<Weighting>(c.get<uint32_t>());
  h.k = c.get<uint32_t>();
  h.levels = c.get<uint32_t>();
  h.words = c.get<uint64_t>();
  h.seed = c.get<uint64_t>();
  h.training_hash = c.get<uint64_t>();
  h.training_descriptors = c.get<uint64_t>();
  h.training_images = c.get<uint64_t>();
  *payload = c.get<uint64_t>();
  *checksum = c.get<uint64_t>();
  h.payload_checksum = *checksum;
  if (h.version >= 3) {  // versions 1-2 left these bytes zero: extractor unknown
    ExtractorSettings& e = h.extractor;
    e.kind = static_cast<ExtractorKind>(c.get<uint32_t>());
    e.features = c.get<uint32_t>();
    e.scale_factor = c.get<float>();
    e.levels = c.get<uint32_t>();
    e.ini_fast = c.get<uint32_t>();
    e.min_fast = c.get<uint32_t>();
    e.cell_px = c.get<uint32_t>();
    e.max_side = c.get<uint32_t>();
  }
  return h;
}

void checkDescriptorBits(const std::string& path, const ModelHeader& h) {
  if (h.descriptor_bits != 256) {
    throw PlaceError(path + ": vocabulary of " + std::to_string(h.descriptor_bits) +
                     "-bit descriptors; binloop uses 256-bit ORB descriptors");
  }
}

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
  s << modelTypeName(type) << " model, " << descriptor_bits << "-bit descriptors, k=" << k
    << " levels=" << levels << " words=" << words << ", trained with seed " << seed << " on "
    << training_descriptors << " descriptors of " << training_images << " images (data hash " << std::hex
    << training_hash << std::dec << ") from " << extractor.describe();
  return s.str();
}

void checkModelExtractor(const std::string& path, const ModelHeader& h, const ExtractorCheck& c) {
  if (!c.expected.known() || h.extractor == c.expected) return;
  const auto warn = [&](const std::string& line) {
    if (c.warn) {
      c.warn(line);
    } else {
      std::cerr << "warning: " << line << std::endl;
    }
  };
  if (c.images_as_they_come && h.extractor.known()) {
    ExtractorSettings scaled = c.expected;
    scaled.max_side = h.extractor.max_side;
    if (h.extractor == scaled) {
      warn(path + ": trained on images scaled to a longer side <= " + std::to_string(h.extractor.max_side) +
           " px; these are described at the size they come in");
      return;
    }
  }
  if (!h.extractor.known()) {
    warn(path + ": the model file (version " + std::to_string(h.version) +
         ") does not record which extractor it was trained with; descriptors will come from " +
         c.expected.describe() + " (retrain it if they differ)");
    return;
  }
  const std::string what = path + ": trained on descriptors of " + h.extractor.describe() +
                           ", but they will come from " + c.expected.describe() +
                           " (differ: " + h.extractor.differences(c.expected) + ")";
  if (!c.force) {
    throw PlaceError(what +
                     "; a vocabulary only fits descriptors like those it was trained on: retrain it with "
                     "these settings, or use it anyway with " +
                     c.force_hint);
  }
  warn(what + "; used anyway (" + c.force_hint + ")");
}

void checkModelExtractor(const std::string& path, const ExtractorCheck& c) {
  if (c.expected.known()) checkModelExtractor(path, readModelHeader(path), c);
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
  const ExtractorSettings& e = header_.extractor;  // version 3, bytes 88-119
  c.put(static_cast<uint32_t>(e.kind));
  c.put(e.features);
  c.put(e.scale_factor);
  c.put(e.levels);
  c.put(e.ini_fast);
  c.put(e.min_fast);
  c.put(e.cell_px);
  c.put(e.max_side);
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
  uint64_t payload = 0, checksum = 0;
  header_ = decodeHeader(path, file_, size, &payload, &checksum);
  version_ = header_.version;
  if (size != kHeaderBytes + payload) {
    throw PlaceError(path + ": truncated model file: header promises " +
                     std::to_string(kHeaderBytes + payload) + " bytes, file has " + std::to_string(size));
  }
  const uint64_t computed =
      version_ == 1 ? hashBytes(file_ + kHeaderBytes, payload) : checksum64(file_ + kHeaderBytes, payload);
  if (computed != checksum) throw PlaceError(path + ": corrupt model file (payload checksum differs)");
  checkDescriptorBits(path, header_);
  pos_ = kHeaderBytes;
}

ModelHeader readModelHeader(const std::string& path) {
  uint8_t bytes[kHeaderBytes] = {};
  std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  std::error_code ec;
  if (!f || !std::filesystem::is_regular_file(path, ec)) throw PlaceError(path + ": cannot open model file");
  const size_t n = std::fread(bytes, 1, kHeaderBytes, f.get());
  uint64_t payload = 0, checksum = 0;
  ModelHeader h = decodeHeader(path, bytes, n, &payload, &checksum);
  checkDescriptorBits(path, h);
  return h;
}

std::string modelIdentity(const ModelHeader& h) {
  char buf[160];
  std::snprintf(buf, sizeof buf, "%s vocabulary of %llu words (training data %016llx, checksum %016llx)",
                modelTypeName(h.type).c_str(), static_cast<unsigned long long>(h.words),
                static_cast<unsigned long long>(h.training_hash),
                static_cast<unsigned long long>(h.payload_checksum));
  return buf;
}

void ModelReader::expectType(ModelType t) const {
  if (header_.type != t) {
    throw PlaceError(path_ + ": holds a " + modelTypeName(header_.type) + " model, expected " +
                     modelTypeName(t));
  }
}

const uint8_t* ModelReader::next(const char* tag4, uint32_t elem_size, uint64_t* count) {
  const std::string want(tag4, 4);
  if (pos_ + 16 > file_size_) throw PlaceError(path_ + ": section '" + want + "' missing (file ends)");
  const std::string tag(reinterpret_cast<const char*>(file_ + pos_), 4);
  uint32_t es;
  std::memcpy(&es, file_ + pos_ + 4, 4);
  std::memcpy(count, file_ + pos_ + 8, 8);
  if (tag != want) throw PlaceError(path_ + ": expected section '" + want + "', found '" + tag + "'");
  if (es != elem_size) {
    throw PlaceError(path_ + ": section '" + want + "' has " + std::to_string(es) +
                     "-byte elements, expected " + std::to_string(elem_size));
  }
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
