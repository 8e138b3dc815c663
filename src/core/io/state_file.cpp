#include "binloop/io/state_file.h"

#include <algorithm>
#include <fstream>

#include "binloop/io/durable_file.h"
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

StateWriter::StateWriter(std::string path, std::string stage, uint64_t map_id)
    : path_(std::move(path)), stage_(std::move(stage)), map_id_(map_id) {}

void StateWriter::putString(const std::string& s) {
  put<uint64_t>(s.size());
  bytes_.insert(bytes_.end(), s.begin(), s.end());
}

void StateWriter::finish() {
  std::vector<uint8_t> head(kHeaderBytes + stage_.size() + sizeof(uint64_t));
  std::memcpy(head.data(), kMagic, 8);
  store<uint32_t>(head.data() + 8, kVersion);
  store<uint32_t>(head.data() + 12, static_cast<uint32_t>(stage_.size()));
  store<uint64_t>(head.data() + 16, bytes_.size());
  store<uint64_t>(head.data() + 24, checksum64(bytes_.data(), bytes_.size()));
  std::memcpy(head.data() + kHeaderBytes, stage_.data(), stage_.size());
  store<uint64_t>(head.data() + kHeaderBytes + stage_.size(), map_id_);
  writeDurably(path_, {{head.data(), head.size()}, {bytes_.data(), bytes_.size()}});
}

namespace {

// The header, the stage's name and the map id of `path`, checked against `stage`; `in` is left at the
// payload.
struct Preamble {
  uint64_t payload = 0, checksum = 0, map_id = 0;
};

Preamble readPreamble(std::ifstream& in, const std::string& path, const std::string& stage) {
  if (!in) throw dataError(path, 0, "no such state file");
  in.seekg(0, std::ios::end);
  const uint64_t size = static_cast<uint64_t>(in.tellg());
  in.seekg(0);
  if (size < kHeaderBytes) {
    throw dataError(path, 0,
                    "not a binloop state file (" + std::to_string(size) + " bytes, shorter than a header)");
  }
  uint8_t header[kHeaderBytes];
  in.read(reinterpret_cast<char*>(header), kHeaderBytes);
  if (std::memcmp(header, kMagic, 8) != 0)
    throw dataError(path, 0, "not a binloop state file (no BLSTATE1 magic)");
  const uint32_t version = load<uint32_t>(header + 8);
  if (version != 2 && version != StateWriter::kVersion) {
    throw dataError(path, 0,
                    "state file version " + std::to_string(version) + ", this binloop reads versions 2 and " +
                        std::to_string(StateWriter::kVersion));
  }
  const uint64_t name_bytes = load<uint32_t>(header + 12);
  const uint64_t id_bytes = version >= 3 ? sizeof(uint64_t) : 0;
  Preamble p;
  p.payload = load<uint64_t>(header + 16);
  p.checksum = load<uint64_t>(header + 24);
  // Compared piece by piece: a corrupt size must not wrap the sum round to the file's size.
  const uint64_t rest = size - kHeaderBytes;
  if (name_bytes > rest || id_bytes > rest - name_bytes || p.payload != rest - name_bytes - id_bytes) {
    throw dataError(path, 0,
                    "truncated state file (" + std::to_string(size) + " bytes, the header announces " +
                        std::to_string(name_bytes) + " of name and " + std::to_string(p.payload) +
                        " of payload after its " + std::to_string(kHeaderBytes) + ")");
  }
  std::string name(name_bytes, '\0');
  in.read(name.data(), static_cast<std::streamsize>(name_bytes));
  if (name != stage)
    throw dataError(path, 0, "this is the " + name + " stage's state, not the " + stage + " stage's");
  if (id_bytes) {
    uint8_t id[sizeof(uint64_t)];
    in.read(reinterpret_cast<char*>(id), sizeof id);
    p.map_id = load<uint64_t>(id);
  }
  if (!in) throw dataError(path, 0, "reading the state file failed");
  return p;
}

}  // namespace

uint64_t stateFileMapId(const std::string& path, const std::string& stage) {
  std::ifstream in(path, std::ios::binary);
  return readPreamble(in, path, stage).map_id;
}

StateReader::StateReader(std::string path, const std::string& stage) : path_(std::move(path)) {
  std::ifstream in(path_, std::ios::binary);
  const Preamble p = readPreamble(in, path_, stage);
  map_id_ = p.map_id;
  bytes_.resize(p.payload);
  in.read(reinterpret_cast<char*>(bytes_.data()), static_cast<std::streamsize>(p.payload));
  if (!in) throw dataError(path_, 0, "reading the state file failed");
  if (checksum64(bytes_.data(), bytes_.size()) != p.checksum)
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
