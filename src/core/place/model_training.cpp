#include "binloop/place/model_training.h"

#include <cmath>

#include "binloop/place/fabmap_recognizer.h"
#include "binloop/place/pq_codebooks.h"
#include "binloop/place/vlad_vocabulary.h"
#include "binloop/util/hash_random.h"

namespace binloop {

uint64_t trainingHash(const std::vector<Descriptors>& images) {
  uint64_t h = 0x6269'6e6c'6f6f'70ull;
  for (const auto& im : images)
    h = hashCombine(h, hashBytes(im.data(), im.size() * sizeof(Desc256), im.size()));
  return h;
}

void saveHbowModel(const VocabularyTree& t, ModelHeader h, const std::string& out) {
  h.type = ModelType::kHbow;
  h.weighting = t.weighting();
  h.k = static_cast<uint32_t>(t.k());
  h.levels = static_cast<uint32_t>(t.levels());
  h.words = t.words();
  ModelWriter w(h);
  t.write(w);
  w.save(out);
}

namespace {

// FAB-MAP: a flat vocabulary, the Chow-Liu tree of its words' presence and the sampled places.
void saveFabmapModel(const std::vector<Descriptors>& images, const TrainOptions& o,
                     const ProgressFn& progress, ModelHeader* h, const std::string& out) {
  FlatVocabParams fp;
  fp.words = o.words;
  fp.seed = o.seed;
  fp.max_training_descriptors = o.max_descriptors;
  FabmapModel m;
  m.vocabulary = std::make_shared<FlatVocabulary>(FlatVocabulary::train(images, fp, progress));
  std::vector<std::vector<uint32_t>> presence;
  presence.reserve(images.size());
  for (const auto& im : images) presence.push_back(m.vocabulary->presence(im));
  m.tree = std::make_shared<ChowLiuTree>(
      ChowLiuTree::learn(presence, static_cast<uint32_t>(m.vocabulary->size()), 0.5, progress));
  // Evenly spaced training places stand for "somewhere new" in the sampled evidence (eq. 3.19).
  const size_t step = std::max<size_t>(1, presence.size() / std::max<size_t>(1, o.fabmap_samples));
  for (size_t i = 0; i < presence.size() && m.samples.size() < o.fabmap_samples; i += step)
    m.samples.push_back(presence[i]);
  h->k = static_cast<uint32_t>(m.vocabulary->size());
  h->levels = 1;
  h->words = m.vocabulary->size();
  h->weighting = Weighting::kBinary;
  ModelWriter w(*h);
  m.write(w);
  w.save(out);
}

}  // namespace

ModelHeader trainModel(ModelType type, const std::vector<Descriptors>& images, const TrainOptions& o,
                       const std::string& out, const ProgressFn& progress) {
  ModelHeader h;
  h.type = type;
  h.seed = o.seed;
  h.extractor = o.extractor;
  h.training_hash = trainingHash(images);
  h.training_images = images.size();
  for (const auto& im : images) h.training_descriptors += im.size();
  auto vladParams = [&](int k_default, int levels_default) {
    VladParams p;
    p.k = o.k ? o.k : k_default;
    p.levels = o.levels ? o.levels : levels_default;
    p.alpha = o.alpha;
    p.pca_dims = o.pca_dims;
    p.seed = o.seed;
    p.max_training_descriptors = o.max_descriptors;
    h.k = static_cast<uint32_t>(p.k);
    h.levels = static_cast<uint32_t>(p.levels);
    h.words = static_cast<uint64_t>(std::pow(p.k, p.levels));
    return p;
  };
  switch (type) {
    case ModelType::kHbow: {
      VocabTreeParams p;
      p.k = o.k ? o.k : 10;
      p.levels = o.levels ? o.levels : 6;
      p.seed = o.seed;
      const VocabularyTree t = VocabularyTree::train(images, p, progress);
      h.k = static_cast<uint32_t>(t.k());
      h.levels = static_cast<uint32_t>(t.levels());
      h.words = t.words();
      saveHbowModel(t, h, out);
      return h;
    }
    case ModelType::kVlad:
    case ModelType::kHmvlad: {
      const bool hier = type == ModelType::kHmvlad;
      const VladVocabulary v =
          VladVocabulary::train(images, vladParams(hier ? 2 : 4, hier ? 2 : 1), progress);
      if (hier && v.levels() < 2) throw PlaceError("hmvlad needs --levels 2 or more");
      ModelWriter w(h);
      v.write(w);
      w.save(out);
      return h;
    }
    case ModelType::kVladPq: {
      const VladVocabulary v = VladVocabulary::train(images, vladParams(4, 1), progress);
      std::vector<std::vector<float>> vlads;
      for (const auto& im : images)
        if (!im.empty()) vlads.push_back(v.aggregate(im).back());
      const PqCodebooks pq =
          PqCodebooks::train(vlads, v.wordsAtLevel(v.levels()), v.dims(), o.pq_codes, o.seed);
      ModelWriter w(h);
      v.write(w);
      pq.write(w);
      w.save(out);
      return h;
    }
    case ModelType::kFabmap:
      saveFabmapModel(images, o, progress, &h, out);
      return h;
  }
  throw PlaceError("unknown model type");
}

}  // namespace binloop
