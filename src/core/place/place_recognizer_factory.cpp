// The factory: model name → recognizer with its model file loaded.
#include "binloop/place/fabmap_recognizer.h"
#include "binloop/place/hbow_recognizer.h"
#include "binloop/place/hmvlad_recognizer.h"
#include "binloop/place/place_error.h"
#include "binloop/place/vlad_recognizer.h"
#include "binloop/place/vladpq_recognizer.h"

namespace binloop {

const std::vector<std::string>& placeModelNames() {
  static const std::vector<std::string> names{"hbow", "fabmap", "vlad", "hmvlad", "vladpq"};
  return names;
}

namespace {

std::unique_ptr<PlaceRecognizer> make(ModelType type, const RecognizerOptions& o) {
  switch (type) {
    case ModelType::kHbow:
      return std::make_unique<HbowRecognizer>(HbowRecognizer::loadVocabulary(o.model_file), o.hbow_min_bar);
    case ModelType::kVlad:
      return std::make_unique<VladRecognizer>(VladRecognizer::loadVocabulary(o.model_file, type),
                                              o.vlad_reference_rank);
    case ModelType::kHmvlad:
      return std::make_unique<HmvladRecognizer>(VladRecognizer::loadVocabulary(o.model_file, type),
                                                o.vlad_reference_rank);
    case ModelType::kVladPq:
      return std::make_unique<VladPqRecognizer>(VladPqModel::load(o.model_file), PqVerify::kHamming,
                                                o.vladpq_shared_slack, o.vlad_reference_rank);
    case ModelType::kFabmap: {
      FabmapModel m = FabmapModel::load(o.model_file);
      m.params.l2_offset = o.fabmap_l2_offset;
      return std::make_unique<FabmapRecognizer>(std::move(m));
    }
  }
  return nullptr;
}

}  // namespace

std::unique_ptr<PlaceRecognizer> makePlaceRecognizer(const std::string& name, const RecognizerOptions& o) {
  const ModelType type = modelTypeFromName(name);  // throws on an unknown name
  if (o.model_file.empty()) throw PlaceError(name + ": no model file given");
  checkModelExtractor(o.model_file, o.extractor);  // reads the header only; before the (large) load
  auto rec = make(type, o);
  if (!rec) throw PlaceError("unknown model '" + name + "'");
  rec->setRanking(o.ranking);
  return rec;
}

}  // namespace binloop
