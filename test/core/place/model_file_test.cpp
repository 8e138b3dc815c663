#include "binloop/place/model_file.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <cstring>
#include <fstream>
#include <iterator>

#include "binloop/place/hbow_recognizer.h"
#include "binloop/place/model_training.h"
#include "binloop/place/place_recognizer.h"
#include "place_test_data.h"
#include "support/test_support.h"

using namespace binloop;
using namespace binloop::test;

namespace {

std::string trainSmallHbow(const TempDir& dir) {
  std::vector<Descriptors> images;
  for (int p = 0; p < 10; ++p) images.push_back(randomPlace(3, p, 100));
  TrainOptions o;
  o.k = 4;
  o.levels = 2;
  trainModel(ModelType::kHbow, images, o, dir / "hbow.bin");
  return dir / "hbow.bin";
}

}  // namespace

TEST(ModelFile, HeaderRecordsHowTheModelWasTrained) {
  TempDir dir;
  const ModelReader r(trainSmallHbow(dir));
  EXPECT_EQ(r.header().type, ModelType::kHbow);
  EXPECT_EQ(r.header().k, 4u);
  EXPECT_EQ(r.header().levels, 2u);
  EXPECT_EQ(r.header().training_descriptors, 1000u);
  EXPECT_EQ(r.header().training_images, 10u);
  EXPECT_NE(r.header().training_hash, 0u);
}

TEST(ModelFile, TruncatedFileIsRefused) {
  TempDir dir;
  const std::string f = trainSmallHbow(dir);
  std::filesystem::resize_file(f, std::filesystem::file_size(f) - 10);
  EXPECT_THROW_WITH(makePlaceRecognizer("hbow", {f}), PlaceError, "truncated model file: header promises");
  std::filesystem::resize_file(f, 50);
  EXPECT_THROW_WITH(makePlaceRecognizer("hbow", {f}), PlaceError, "truncated model file (50 bytes");
}

TEST(ModelFile, CorruptPayloadIsRefused) {
  TempDir dir;
  const std::string f = trainSmallHbow(dir);
  std::fstream s(f, std::ios::in | std::ios::out | std::ios::binary);
  s.seekp(300);
  s.put('\x5a');
  s.close();
  EXPECT_THROW_WITH(makePlaceRecognizer("hbow", {f}), PlaceError, "corrupt model file (payload checksum differs)");
}

TEST(ModelFile, WrongDescriptorSizeIsRefused) {
  TempDir dir;
  ModelHeader h;
  h.descriptor_bits = 512;
  ModelWriter(h).save(dir / "wide.bin");
  EXPECT_THROW_WITH(ModelReader(dir / "wide.bin"), PlaceError, "vocabulary of 512-bit descriptors; binloop uses 256-bit");
  EXPECT_THROW_WITH(descriptorsFromMat(cv::Mat(5, 64, CV_8U)), PlaceError, "32-byte binary rows");
  EXPECT_THROW_WITH(descriptorsFromMat(cv::Mat(5, 32, CV_32F)), PlaceError, "got 32 columns of depth 5");
}

TEST(ModelFile, WrongModelTypeAndUnknownNamesAreRefused) {
  TempDir dir;
  const std::string f = trainSmallHbow(dir);
  EXPECT_THROW_WITH(makePlaceRecognizer("vlad", {f}), PlaceError, "holds a hbow model, expected vlad");
  EXPECT_THROW_WITH(makePlaceRecognizer("netvlad", {f}), PlaceError,
                    "unknown model 'netvlad' (known: hbow, fabmap, vlad, hmvlad, vladpq)");
  writeText(dir / "voc.txt", "10 6 0 0\n");
  EXPECT_THROW_WITH(makePlaceRecognizer("hbow", {dir / "voc.txt"}), PlaceError, "not a binloop model file");
  EXPECT_THROW_WITH(makePlaceRecognizer("hbow", {dir / "none.bin"}), PlaceError, "cannot open model file");
}

TEST(ModelFile, EmptyDescriptorSetAndDuplicateKeyframeAreRefused) {
  TempDir dir;
  auto rec = makePlaceRecognizer("hbow", {trainSmallHbow(dir)});
  EXPECT_THROW_WITH(rec->add(7, {}), PlaceError, "hbow: keyframe 7 has no descriptors");
  rec->add(7, randomPlace(3, 1, 50));
  EXPECT_THROW_WITH(rec->add(7, randomPlace(3, 1, 50)), PlaceError, "keyframe 7 was added before");
  EXPECT_EQ(rec->query(8, {}).status, QueryStatus::kUnknownKeyframe);
  EXPECT_EQ(rec->query(7, {}).status, QueryStatus::kEmptyDatabase);
}

namespace {

// Rewrites a version-2 model file as version 1 wrote it: no padding before sections, the one-word hash.
void rewriteAsVersion1(const std::string& v2, const std::string& v1) {
  std::ifstream in(v2, std::ios::binary);
  std::vector<uint8_t> f((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<uint8_t> payload;
  for (size_t pos = 128; pos < f.size();) {
    uint32_t es;
    uint64_t count;
    std::memcpy(&es, &f[pos + 4], 4);
    std::memcpy(&count, &f[pos + 8], 8);
    const size_t data = (pos + 16 + 63) / 64 * 64;
    payload.insert(payload.end(), f.begin() + static_cast<long>(pos), f.begin() + static_cast<long>(pos + 16));
    payload.insert(payload.end(), f.begin() + static_cast<long>(data), f.begin() + static_cast<long>(data + es * count));
    pos = data + es * count;
  }
  std::vector<uint8_t> out(f.begin(), f.begin() + 128);
  const uint32_t version = 1;
  const uint64_t size = payload.size(), checksum = hashBytes(payload.data(), payload.size());
  std::memcpy(&out[8], &version, 4);
  std::memcpy(&out[72], &size, 8);  // after magic, 6 uint32 and 5 uint64 header fields
  std::memcpy(&out[80], &checksum, 8);
  out.insert(out.end(), payload.begin(), payload.end());
  std::ofstream(v1, std::ios::binary).write(reinterpret_cast<const char*>(out.data()), static_cast<long>(out.size()));
}

}  // namespace

TEST(ModelFile, SectionsAreAlignedForUseInPlace) {
  TempDir dir;
  ModelReader r(trainSmallHbow(dir));
  const auto desc = r.view<Desc256>("TDSC");
  const auto first_child = r.view<uint32_t>("TFCH");
  EXPECT_EQ(reinterpret_cast<uintptr_t>(desc.data) % 64, 0u);
  EXPECT_EQ(reinterpret_cast<uintptr_t>(first_child.data) % 64, 0u);
  EXPECT_EQ(desc.size, first_child.size);
  EXPECT_GT(desc.size, 4u);
}

TEST(ModelFile, ReadsVersion1Files) {
  TempDir dir;
  const std::string v2 = trainSmallHbow(dir), v1 = dir / "v1.bin";
  rewriteAsVersion1(v2, v1);
  EXPECT_LT(std::filesystem::file_size(v1), std::filesystem::file_size(v2));  // no padding
  const auto a = HbowRecognizer::loadVocabulary(v2), b = HbowRecognizer::loadVocabulary(v1);
  EXPECT_EQ(a->words(), b->words());
  BowVector va, vb;
  const Descriptors d = randomPlace(3, 11, 200);
  a->transform(d, &va);
  b->transform(d, &vb);
  ASSERT_EQ(va.size(), vb.size());
  for (size_t i = 0; i < va.size(); ++i) EXPECT_EQ(va[i].word, vb[i].word);
  // A version-1 file is checked with its own hash: one flipped byte is still found.
  std::fstream s(v1, std::ios::in | std::ios::out | std::ios::binary);
  s.seekp(200);
  s.put('\x33');
  s.close();
  EXPECT_THROW_WITH(HbowRecognizer::loadVocabulary(v1), PlaceError, "payload checksum differs");
}
