#include "binloop/io/state_file.h"

#include <algorithm>
#include <cstdio>
#include <fstream>

#include "binloop/util/checksum.h"

namespace binloop {
namespace {

constexpr char kMagic[8] = {'B', 'L', 'S', 'T', 'A', 'T', 'E', '1'};
constexpr size_t kHeaderBytes = 32;

template <class T>
void store(uint8_t* at, T v) {
  std::memcpy(at, &v, sizeof(T));
}
template <class T>
T load(const uint8_t* at) {
  T v;
  std::memcpy(&v, at, sizeof(T));
  return v;
}

}  // namespace

std::string stageStatePath(const std::string& directory, const std::string& stage) {
  return directory + "/" + stage + ".state";
}

StateWriter::StateWriter(std::string path, std::string stage) : path_(std::move(path)), stage_(std::move(stage)) {}

void StateWriter::putString(const std::string& s) {
  put<uint64_t>(s.size());
  bytes_.insert(bytes_.end(), s.begin(), s.end());
}

void StateWriter::finish() {
  uint8_t header[kHeaderBytes] = {};
  std::memcpy(header, kMagic, 8);
  store<uint32_t>(header + 8, kVersion);
  store<uint32_t>(header + 12, static_cast<uint32_t>(stage_.size()));
  store<uint64_t>(header + 16, bytes_.size());
  store<uint64_t>(header + 24, checksum64(bytes_.data(), bytes_.size()));
  const std::string partial = path_ + ".partial";
  {
    std::ofstream out(partial, std::ios::binary | std::ios::trunc);
    if (!out) throw dataError(path_, 0, "cannot write the state file (is the folder there and writable?)");
    out.write(reinterpret_cast<const char*>(header), kHeaderBytes);
    out.write(stage_.data(), static_cast<std::streamsize>(stage_.size()));
    out.write(reinterpret_cast<const char*>(bytes_.data()), static_cast<std::streamsize>(bytes_.size()));
    out.flush();
    if (!out) {
      std::remove(partial.c_str());
      throw dataError(path_, 0, "writing the state file failed (disk full?)");
    }
  }
  if (std::rename(partial.c_str(), path_.c_str()) != 0) {
    std::remove(partial.c_str());
    throw dataError(path_, 0, "cannot rename " + partial + " to it");
  }
}

StateReader::StateReader(std::string path, const std::string& stage) : path_(std::move(path)) {
  std::ifstream in(path_, std::ios::binary | std::ios::ate);
  if (!in) throw dataError(path_, 0, "no such state file");
  const std::streamoff size = in.tellg();
  in.seekg(0);
  if (size < static_cast<std::streamoff>(kHeaderBytes))
    throw dataError(path_, 0, "not a binloop state file (" + std::to_string(size) + " bytes, shorter than a header)");
  uint8_t header[kHeaderBytes];
  in.read(reinterpret_cast<char*>(header), kHeaderBytes);
  if (std::memcmp(header, kMagic, 8) != 0) throw dataError(path_, 0, "not a binloop state file (no BLSTATE1 magic)");
  const uint32_t version = load<uint32_t>(header + 8);
  if (version != StateWriter::kVersion)
    throw dataError(path_, 0, "state file version " + std::to_string(version) + ", this binloop reads version " +
                                  std::to_string(StateWriter::kVersion));
  const uint32_t name_bytes = load<uint32_t>(header + 12);
  const uint64_t payload = load<uint64_t>(header + 16);
  const uint64_t checksum = load<uint64_t>(header + 24);
  if (static_cast<uint64_t>(size) != kHeaderBytes + name_bytes + payload)
    throw dataError(path_, 0, "truncated state file (" + std::to_string(size) + " bytes, the header announces " +
                                  std::to_string(kHeaderBytes + name_bytes + payload) + ")");
  std::string name(name_bytes, '\0');
  in.read(name.data(), name_bytes);
  if (name != stage) throw dataError(path_, 0, "this is the " + name + " stage's state, not the " + stage + " stage's");
  bytes_.resize(payload);
  in.read(reinterpret_cast<char*>(bytes_.data()), static_cast<std::streamsize>(payload));
  if (!in) throw dataError(path_, 0, "reading the state file failed");
  if (checksum64(bytes_.data(), bytes_.size()) != checksum)
    throw dataError(path_, 0, "corrupt state file (payload checksum differs)");
}

const uint8_t* StateReader::take(size_t n, const char* what) {
  if (n > bytes_.size() - pos_) fail(std::string("ends early, in ") + what);
  const uint8_t* p = bytes_.data() + pos_;
  pos_ += n;
  return p;
}

std::string StateReader::getString(const char* what) {
  const uint64_t n = getCount(what);
  const uint8_t* p = take(n, what);
  return std::string(reinterpret_cast<const char*>(p), n);
}

uint64_t StateReader::getCount(const char* what, size_t min_record_bytes) {
  const uint64_t n = get<uint64_t>(what);
  if (n > (bytes_.size() - pos_) / std::max<size_t>(1, min_record_bytes))
    fail(std::string("impossible count ") + std::to_string(n) + " in " + what);
  return n;
}

void StateReader::expectEnd() {
  if (pos_ != bytes_.size())
    fail(std::to_string(bytes_.size() - pos_) + " bytes left over after the state (written by other code?)");
}

void StateReader::fail(const std::string& what) const { throw dataError(path_, 0, what); }

}  // namespace binloop
