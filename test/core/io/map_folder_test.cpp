// A saved map folder as a transaction (include/binloop/io/map_folder.h) and the state file's header
// (include/binloop/io/state_file.h): map ids, the swap of a new folder for the old, refusals that change
// nothing.
#include "binloop/io/map_folder.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <stdexcept>

#include "binloop/io/data_error.h"
#include "binloop/io/state_file.h"
#include "support/test_support.h"

namespace binloop {
namespace {
namespace fs = std::filesystem;

// The smallest stage: a list of numbers.
struct ToyStage {
  std::vector<uint32_t> values;
  void save(StateWriter& w) const { w.putArray(values); }
  void load(StateReader& r) {
    values = r.getArray<uint32_t>("values");
    r.expectEnd();
  }
};

const std::vector<std::string> kStages = {"tracking", "local_mapping"};

std::string bytesOf(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void writeBytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

// A map of both toy stages saved into `dir` as one transaction; returns its id.
uint64_t saveToyMap(const std::string& dir, uint32_t value) {
  MapSave save(dir);
  for (const std::string& s : kStages)
    saveStateFile(ToyStage{{value, value + 1}}, stageStatePath(save.staging(), s), s, save.mapId());
  save.commit();
  return save.mapId();
}

TEST(MapFolder, MapIdsAreNeverZeroAndNeverRepeat) {
  std::set<uint64_t> ids;
  for (int i = 0; i < 1000; ++i) ids.insert(newMapId());
  EXPECT_EQ(ids.size(), 1000u);
  EXPECT_EQ(ids.count(0), 0u);
  EXPECT_EQ(mapIdText(0x1234), "0000000000001234");
}

TEST(MapFolder, ASaveReplacesTheOldMapWholeAndLeavesNoStagingFolder) {
  test::TempDir tmp;
  const std::string dir = tmp / "map";
  const uint64_t first = saveToyMap(dir, 1);
  EXPECT_EQ(checkMapFolder(dir, kStages), first);
  const uint64_t second = saveToyMap(dir + "/", 7);  // a trailing slash names the same folder
  EXPECT_NE(first, second);
  EXPECT_EQ(checkMapFolder(dir, kStages), second);
  for (const std::string& s : kStages) {
    ToyStage t;
    EXPECT_EQ(loadStateFile(t, stageStatePath(dir, s), s), second);
    EXPECT_EQ(t.values, (std::vector<uint32_t>{7, 8}));
  }
  size_t entries = 0;
  for (const auto& e : fs::directory_iterator(tmp.path())) {
    ++entries;
    EXPECT_EQ(e.path().filename(), "map") << "left behind: " << e.path();
  }
  EXPECT_EQ(entries, 1u);
}

TEST(MapFolder, ASaveThatFailsHalfwayLeavesTheOldMapByteForByte) {
  test::TempDir tmp;
  const std::string dir = tmp / "map";
  saveToyMap(dir, 1);
  const std::string before = bytesOf(stageStatePath(dir, "tracking"));
  try {
    MapSave save(dir);
    saveStateFile(ToyStage{{9}}, stageStatePath(save.staging(), "tracking"), "tracking", save.mapId());
    throw std::runtime_error("the second stage failed");  // never committed
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(bytesOf(stageStatePath(dir, "tracking")), before);
  EXPECT_NO_THROW(checkMapFolder(dir, kStages));
  EXPECT_EQ(std::distance(fs::directory_iterator(tmp.path()), fs::directory_iterator()), 1);
}

TEST(MapFolder, AFolderWithOtherFilesIsNotReplaced) {
  test::TempDir tmp;
  const std::string dir = tmp / "home";
  fs::create_directories(dir);
  writeBytes(dir + "/notes.txt", "mine");
  EXPECT_THROW_WITH(MapSave save(dir), DataError, "holds 'notes.txt', which is not a saved map's");
  EXPECT_EQ(bytesOf(dir + "/notes.txt"), "mine");
  writeBytes(tmp / "file", "x");
  EXPECT_THROW_WITH(MapSave save(tmp / "file"), DataError, "is a file, not a map folder");
}

TEST(MapFolder, AFolderMixingTwoSavesIsRefusedNamingTheFile) {
  test::TempDir tmp;
  saveToyMap(tmp / "a", 1);
  const uint64_t b = saveToyMap(tmp / "b", 2);
  fs::copy_file(stageStatePath(tmp / "b", "local_mapping"), stageStatePath(tmp / "a", "local_mapping"),
                fs::copy_options::overwrite_existing);
  EXPECT_THROW_WITH(checkMapFolder(tmp / "a", kStages), DataError,
                    "local_mapping.state: belongs to map save " + mapIdText(b));
  EXPECT_THROW_WITH(checkMapFolder(tmp / "a", {"tracking", "loop_closing"}), DataError, "no such state file");
  EXPECT_THROW_WITH(checkMapFolder(tmp / "none", kStages), DataError, "no such folder");
}

TEST(MapFolder, AHeaderWhoseSizesWrapIsRefusedAsTruncated) {
  test::TempDir tmp;
  saveToyMap(tmp / "m", 1);
  const std::string path = stageStatePath(tmp / "m", "tracking");
  std::string bytes = bytesOf(path);
  // The name's length (offset 12) 2^31 more and the payload's (offset 16) 2^31 less, modulo 2^64: the sum is
  // the file's size again, so only checking each against what is left stops a 2 GiB allocation.
  uint32_t name_bytes;
  uint64_t payload;
  std::memcpy(&name_bytes, &bytes[12], sizeof name_bytes);
  std::memcpy(&payload, &bytes[16], sizeof payload);
  name_bytes += uint32_t{1} << 31;
  payload -= uint64_t{1} << 31;
  std::memcpy(&bytes[12], &name_bytes, sizeof name_bytes);
  std::memcpy(&bytes[16], &payload, sizeof payload);
  writeBytes(path, bytes);
  EXPECT_THROW_WITH(checkMapFolder(tmp / "m", kStages), DataError, "truncated state file");
  ToyStage t;
  EXPECT_THROW_WITH(loadStateFile(t, path, "tracking"), DataError, "truncated state file");
}

TEST(MapFolder, AStateFileOfVersionTwoReadsWithMapIdZero) {
  test::TempDir tmp;
  saveToyMap(tmp / "m", 5);
  const std::string path = stageStatePath(tmp / "m", "tracking");
  std::string bytes = bytesOf(path);
  // version 2: the same header and payload without the 8 bytes of map id after the name
  const uint32_t v2 = 2;
  std::memcpy(&bytes[8], &v2, sizeof v2);
  bytes.erase(32 + std::string("tracking").size(), 8);
  writeBytes(path, bytes);
  ToyStage t;
  EXPECT_EQ(loadStateFile(t, path, "tracking"), 0u);
  EXPECT_EQ(t.values, (std::vector<uint32_t>{5, 6}));
}

}  // namespace
}  // namespace binloop
