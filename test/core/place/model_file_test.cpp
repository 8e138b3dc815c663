#include "binloop/place/model_file.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "binloop/features/orb_slam_extractor.h"
#include "binloop/place/hbow_recognizer.h"
#include "binloop/place/model_training.h"
#include "binloop/place/place_recognizer.h"
#include "place_test_data.h"
#include "support/test_support.h"

using namespace binloop;
using namespace binloop::test;

namespace {

std::string trainSmallHbow(const TempDir& dir, const ExtractorSettings& extractor = {}) {
  std::vector<Descriptors> images;
  for (int p = 0; p < 10; ++p) images.push_back(randomPlace(3, p, 100));
  TrainOptions o;
  o.k = 4;
  o.levels = 2;
  o.extractor = extractor;
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
  EXPECT_THROW_WITH(makePlaceRecognizer("hbow", {f}), PlaceError,
                    "corrupt model file (payload checksum differs)");
}

TEST(ModelFile, WrongDescriptorSizeIsRefused) {
  TempDir dir;
  ModelHeader h;
  h.descriptor_bits = 512;
  ModelWriter(h).save(dir / "wide.bin");
  EXPECT_THROW_WITH(ModelReader(dir / "wide.bin"), PlaceError,
                    "vocabulary of 512-bit descriptors; binloop uses 256-bit");
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

// Rewrites a version-3 model file as version 1 wrote it: no padding before sections, the one-word hash (the
// extractor record in bytes 88-119 is left; version 1 never reads it).
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
    payload.insert(payload.end(), f.begin() + static_cast<long>(pos),
                   f.begin() + static_cast<long>(pos + 16));
    payload.insert(payload.end(), f.begin() + static_cast<long>(data),
                   f.begin() + static_cast<long>(data + es * count));
    pos = data + es * count;
  }
  std::vector<uint8_t> out(f.begin(), f.begin() + 128);
  const uint32_t version = 1;
  const uint64_t size = payload.size(), checksum = hashBytes(payload.data(), payload.size());
  std::memcpy(&out[8], &version, 4);
  std::memcpy(&out[72], &size, 8);  // after magic, 6 uint32 and 5 uint64 header fields
  std::memcpy(&out[80], &checksum, 8);
  out.insert(out.end(), payload.begin(), payload.end());
  std::ofstream(v1, std::ios::binary)
      .write(reinterpret_cast<const char*>(out.data()), static_cast<long>(out.size()));
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

namespace {

// The SLAM's extractor settings (OrbSlamParams defaults, config/kitti.yaml) and, optionally, other ones.
ExtractorSettings slamExtractor(int features = 2000, int max_side = 0) {
  OrbSlamParams p;
  p.features = features;
  return extractorSettings(p, max_side);
}

// Rewrites a version-3 file as version 2 wrote it: the same layout, with no extractor record.
void rewriteAsVersion2(const std::string& v3, const std::string& v2) {
  std::ifstream in(v3, std::ios::binary);
  std::vector<uint8_t> f((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const uint32_t version = 2;
  std::memcpy(&f[8], &version, 4);
  std::fill(f.begin() + 88, f.begin() + 128, 0);
  std::ofstream(v2, std::ios::binary)
      .write(reinterpret_cast<const char*>(f.data()), static_cast<long>(f.size()));
}

}  // namespace

TEST(ModelFile, HeaderRecordsTheExtractorAndItsSettings) {
  TempDir dir;
  OrbSlamParams p;
  p.features = 1500;
  p.scale_factor = 1.25f;
  p.levels = 6;
  p.ini_fast = 18;
  p.min_fast = 5;
  p.cell_px = 40;
  const ExtractorSettings e = extractorSettings(p, 1024);
  const std::string f = trainSmallHbow(dir, e);
  for (const ModelHeader& h : {ModelReader(f).header(), readModelHeader(f)}) {
    EXPECT_EQ(h.version, 3u);
    EXPECT_EQ(h.extractor.kind, ExtractorKind::kBinloopOrb);
    EXPECT_EQ(h.extractor.features, 1500u);
    EXPECT_EQ(h.extractor.scale_factor, 1.25f);
    EXPECT_EQ(h.extractor.levels, 6u);
    EXPECT_EQ(h.extractor.ini_fast, 18u);
    EXPECT_EQ(h.extractor.min_fast, 5u);
    EXPECT_EQ(h.extractor.cell_px, 40u);
    EXPECT_EQ(h.extractor.max_side, 1024u);
    EXPECT_EQ(h.extractor, e);
    EXPECT_EQ(h.k, 4u);  // the fields before the record are where they were
    EXPECT_EQ(h.training_images, 10u);
  }
  EXPECT_NE(ModelReader(f).header().describe().find(
                "from binloop ORB with the Gaussian BRIEF pattern (1500 features, scale 1.25, 6 levels, FAST "
                "18/5, 40-px cells, images scaled to a "
                "longer side <= 1024 px)"),
            std::string::npos)
      << ModelReader(f).header().describe();
  EXPECT_EQ(slamExtractor().describe(),
            "binloop ORB with the Gaussian BRIEF pattern (2000 features, scale 1.2, 8 levels, FAST 20/7, "
            "30-px cells, full-size images)");
  // A model trained from descriptors of unknown origin says so.
  TempDir dir2;
  EXPECT_FALSE(ModelReader(trainSmallHbow(dir2)).header().extractor.known());
  EXPECT_NE(
      ModelReader(dir2 / "hbow.bin").header().describe().find("from an unknown extractor (not recorded)"),
      std::string::npos);
}

TEST(ModelFile, OtherExtractorSettingsAreRefusedWithBothNamed) {
  TempDir dir;
  const std::string f = trainSmallHbow(dir, slamExtractor(1000, 1024));
  RecognizerOptions o{f};
  o.extractor.expected = slamExtractor();
  EXPECT_THROW_WITH(makePlaceRecognizer("hbow", o), PlaceError,
                    f + ": trained on descriptors of binloop ORB with the Gaussian BRIEF pattern (1000 "
                        "features, scale 1.2, 8 levels, FAST 20/7, 30-px cells, "
                        "images scaled to a longer side <= 1024 px), but they will come from binloop ORB "
                        "with the Gaussian BRIEF pattern (2000 features, scale 1.2, "
                        "8 levels, FAST 20/7, 30-px cells, full-size images) (differ: features 1000 vs 2000, "
                        "max side 1024 vs "
                        "none); a vocabulary only fits descriptors like those it was trained on: retrain it "
                        "with these settings, "
                        "or use it anyway with --force-extractor");
  // The hint names what the caller offers (e.g. a SLAM config key).
  o.extractor.force_hint = "orb.force_vocabulary: true";
  EXPECT_THROW_WITH(makePlaceRecognizer("hbow", o), PlaceError,
                    "use it anyway with orb.force_vocabulary: true");
  // Without an expectation nothing is checked (models trained in memory, tests).
  EXPECT_NO_THROW(makePlaceRecognizer("hbow", {f}));
  // An imported DBoW2 vocabulary was trained on another BRIEF pattern.
  ExtractorSettings imported;
  imported.kind = ExtractorKind::kDbow2Import;
  TempDir dir2;
  EXPECT_THROW_WITH(checkModelExtractor(trainSmallHbow(dir2, imported), o.extractor), PlaceError,
                    "(differ: extractor imported DBoW2 vs binloop ORB with the Gaussian BRIEF pattern)");
}

// The SLAM describes its frames at the size they come in; a model trained on scaled-down pictures (the photo
// vocabularies) is loaded with a warning there, and only a difference in the descriptors themselves refuses.
TEST(ModelFile, TheSlamTakesAModelTrainedOnScaledImagesWithAWarning) {
  TempDir dir;
  const std::string f = trainSmallHbow(dir, slamExtractor(2000, 1024));
  std::vector<std::string> warnings;
  ExtractorCheck c;
  c.expected = slamExtractor();
  c.warn = [&](const std::string& w) { warnings.push_back(w); };
  EXPECT_THROW_WITH(checkModelExtractor(f, c), PlaceError, "(differ: max side 1024 vs none)");
  c.images_as_they_come = true;
  EXPECT_NO_THROW(checkModelExtractor(f, c));
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0], f + ": trained on images scaled to a longer side <= 1024 px; these are described at "
                             "the size they come in");
  TempDir dir2;
  EXPECT_THROW_WITH(checkModelExtractor(trainSmallHbow(dir2, slamExtractor(1000, 1024)), c), PlaceError,
                    "(differ: features 1000 vs 2000, max side 1024 vs none)");
}

TEST(ModelFile, ForcedExtractorMismatchWarnsAndLoads) {
  TempDir dir;
  const std::string f = trainSmallHbow(dir, slamExtractor(1000));
  std::vector<std::string> warnings;
  RecognizerOptions o{f};
  o.extractor.expected = slamExtractor();
  o.extractor.force = true;
  o.extractor.warn = [&](const std::string& w) { warnings.push_back(w); };
  std::unique_ptr<PlaceRecognizer> rec;
  ASSERT_NO_THROW(rec = makePlaceRecognizer("hbow", o));
  ASSERT_TRUE(rec);
  rec->add(1, randomPlace(3, 1, 50));
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0],
            f + ": trained on descriptors of binloop ORB with the Gaussian BRIEF pattern (1000 features, "
                "scale 1.2, 8 levels, FAST 20/7, "
                "30-px cells, full-size images), but they will come from binloop ORB with the Gaussian BRIEF "
                "pattern (2000 features, "
                "scale 1.2, 8 levels, FAST 20/7, 30-px cells, full-size images) (differ: features 1000 vs "
                "2000); used anyway (--force-extractor)");
  // Equal settings: no warning.
  warnings.clear();
  TempDir dir2;
  o.model_file = trainSmallHbow(dir2, slamExtractor());
  o.extractor.force = false;
  EXPECT_NO_THROW(makePlaceRecognizer("hbow", o));
  EXPECT_TRUE(warnings.empty());
}

TEST(ModelFile, ReadsVersion2FilesAsExtractorUnknownAndWarns) {
  TempDir dir;
  const std::string v3 = trainSmallHbow(dir, slamExtractor()), v2 = dir / "v2.bin";
  rewriteAsVersion2(v3, v2);
  const ModelReader r(v2);
  EXPECT_EQ(r.header().version, 2u);
  EXPECT_FALSE(r.header().extractor.known());
  EXPECT_EQ(r.header().k, 4u);
  EXPECT_EQ(HbowRecognizer::loadVocabulary(v2)->words(), HbowRecognizer::loadVocabulary(v3)->words());
  std::vector<std::string> warnings;
  RecognizerOptions o{v2};
  o.extractor.expected = slamExtractor();
  o.extractor.warn = [&](const std::string& w) { warnings.push_back(w); };
  EXPECT_NO_THROW(makePlaceRecognizer("hbow", o));  // not forced, still loaded: it may well fit
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0],
            v2 + ": the model file (version 2) does not record which extractor it was trained with; "
                 "descriptors will come from binloop ORB with the Gaussian BRIEF pattern (2000 features, "
                 "scale 1.2, 8 levels, FAST 20/7, "
                 "30-px cells, full-size images) (retrain it if they differ)");
  // A version from the future is refused.
  std::fstream s(v2, std::ios::in | std::ios::out | std::ios::binary);
  const uint32_t v4 = 4;
  s.seekp(8);
  s.write(reinterpret_cast<const char*>(&v4), 4);
  s.close();
  EXPECT_THROW_WITH(readModelHeader(v2), PlaceError,
                    "model file version 4, this build reads versions 1 to 3");
  EXPECT_THROW_WITH(ModelReader{v2}, PlaceError, "model file version 4, this build reads versions 1 to 3");
}
