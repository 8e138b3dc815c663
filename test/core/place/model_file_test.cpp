#include "binloop/place/model_file.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

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
