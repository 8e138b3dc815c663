#pragma once
// The loop-detection stage (step 3 of four; ARCHITECTURE.md): refined keyframes from local mapping in, one
// LoopCandidates per keyframe out (plus one per shadow model). It owns the active place-recognition model,
// every keyframe's descriptors (so that another model can be built from them at any time) and the
// covisibility it has been told about; nothing is shared with the other stages.
//
// Each keyframe is added to the model and queried with its covisible neighbours as the reference that sets
// the bar (the thesis' rule for every model) and the keyframes of the last `ignore_recent` as never
// candidates; candidates that pass go through ORB-SLAM2's consistency check.
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

#include "binloop/loop/consistency_groups.h"
#include "binloop/messages/keyframe.h"
#include "binloop/messages/loop_candidates.h"
#include "binloop/place/place_recognizer.h"

namespace binloop {

class StateWriter;
class StateReader;

struct LoopDetectorParams {
  std::string model = "hmvlad";  // the default model: its file is small enough to ship (docs/loop_models.md)
  int max_reference = 10;        // strongest covisible neighbours that set the bar
  int ignore_recent = 20;        // keyframes just before the query are never candidates (they are not loops)
  int consistency = 2;      // consecutive consistent queries before a candidate is accepted (ORB-SLAM2: 3;
                            // config/kitti.yaml says why 2)
  int consistency_gap = 2;  // queries a chain may skip (ConsistencyGroups' max_gap; ORB-SLAM2: 0)
};

class LoopDetector {
 public:
  /// Makes a model by name (hbow, fabmap, vlad, hmvlad, vladpq); throws PlaceError for an unknown name or
  /// an unusable model file. The runner's factory loads vocab/<dir>/<name>.bin with the extractor check.
  using ModelFactory = std::function<std::unique_ptr<PlaceRecognizer>(const std::string& name)>;

  struct Output {
    msg::LoopCandidatesPtr active;
    std::vector<msg::LoopCandidatesPtr> shadow;
    double switch_ms =
        0;  // building a switched-to model's index from the stored keyframes, when one took over
  };

  /// Throws PlaceError when the first model cannot be made.
  LoopDetector(const LoopDetectorParams& p, ModelFactory make);

  /// Adds the keyframe to every model and queries them. A keyframe seen before (a later revision) only
  /// updates its covisibility. Throws std::invalid_argument for a keyframe without descriptors.
  Output process(const msg::KeyFrame& kf);

  /// The model to use from the next keyframe on. Its index is built from every stored keyframe's
  /// descriptors when that keyframe arrives, so the switch happens at a keyframe boundary. Throws
  /// PlaceError now for a name or model file that cannot be used (the running model stays).
  void switchModel(const std::string& name);
  /// New detection rules and model factory (e.g. other model thresholds, from dynamic_reconfigure): the
  /// model p.model is made now and, like a switch, built from the stored keyframes and takes over at the next
  /// keyframe. Throws PlaceError as switchModel; then nothing changes.
  void reconfigure(const LoopDetectorParams& p, ModelFactory make);
  /// Models queried beside the active one and only logged (shadow mode). Same errors as switchModel.
  void setShadowModels(const std::vector<std::string>& names);

  const std::string& activeModel() const { return active_name_; }
  size_t keyframeCount() const { return order_.size(); }
  /// Keyframes in the active model's index (equal to keyframeCount() except between a switch and the next
  /// keyframe, when the new index is built).
  size_t indexSize() const { return active_.recognizer->size(); }
  size_t indexBytes() const {
    return active_.recognizer->size() * active_.recognizer->indexBytesPerKeyframe();
  }

  /// What a model's index depends on besides the keyframes (its vocabulary file: model_files.h), for the
  /// check when a saved map is loaded; "" = unknown, not checked.
  using ModelIdentity = std::function<std::string(const std::string& name)>;
  void setModelIdentity(ModelIdentity id) { identity_ = std::move(id); }
  /// Every keyframe's descriptors and covisibility, and which models had an index with which vocabulary
  /// (an index is rebuilt from the descriptors on load, so the same keyframes give the same index).
  void save(StateWriter& w) const;
  /// Into a newly made detector: its own models (active and shadow) are built from the saved keyframes.
  /// Throws DataError for a broken file, or when the map's index of a model was built with another vocabulary
  /// than this detector's model of that name.
  void load(StateReader& r);

 private:
  struct Model {
    std::string name;
    std::unique_ptr<PlaceRecognizer> recognizer;
    ConsistencyGroups consistency;
  };
  Model makeModel(const std::string& name) const;
  void fillFrom(Model& m) const;  // every stored keyframe, in order
  /// The models whose index a saved map records: the active one (or the one about to take over) and the
  /// shadows.
  std::vector<std::string> indexedModels() const;
  std::shared_ptr<msg::LoopCandidates> query(Model& m, SlamKeyframeId id, uint64_t frame, bool shadow) const;
  std::vector<KeyframeId> referenceOf(SlamKeyframeId id) const;
  std::set<SlamKeyframeId> groupOf(SlamKeyframeId id) const;

  LoopDetectorParams p_;
  ModelFactory make_;
  Model active_;
  std::string active_name_;
  std::unique_ptr<Model> pending_;  // made by switchModel, filled and swapped in at the next keyframe
  std::vector<Model> shadow_;
  // Dense ids for the models (their KeyframeId is 32-bit, ours carry the issuer).
  std::unordered_map<SlamKeyframeId, KeyframeId> dense_;
  std::vector<SlamKeyframeId> order_;
  std::vector<Descriptors> descriptors_;
  std::unordered_map<SlamKeyframeId, std::map<SlamKeyframeId, uint32_t>> covisible_;  // both directions
  ModelIdentity identity_;
};

}  // namespace binloop
