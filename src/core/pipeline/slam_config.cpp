#include "binloop/pipeline/slam_config.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <opencv2/core.hpp>
#include <sstream>
#include <vector>

namespace binloop {

namespace {

// One setting: where it lives in the structs and the smallest value it accepts.
struct Setting {
  // kSubPixelFit: 0 parabola, 1 equiangular; kPattern: 0 Gaussian, 1 ORB's learned pattern; kCullCount: 0
  // keyframes, 1 a stereo sighting twice, 2 a close stereo sighting twice
  enum Kind { kInt, kFloat, kDouble, kBool, kSubPixelFit, kPattern, kCullCount } kind;
  void* ptr;
  double min;
};

using Sections = std::map<std::string, std::map<std::string, Setting>>;

// Tracking's sections: the extractor, stereo matching, tracking and recovery.
Sections trackingSettings(TrackerParams& t) {
  using S = Setting;
  return {
      {"orb",
       {{"features", {S::kInt, &t.orb.features, 1}},
        {"scale_factor", {S::kFloat, &t.orb.scale_factor, 1.01}},
        {"levels", {S::kInt, &t.orb.levels, 1}},
        {"ini_fast", {S::kInt, &t.orb.ini_fast, 1}},
        {"min_fast", {S::kInt, &t.orb.min_fast, 1}},
        {"learned_pattern", {S::kPattern, &t.orb.pattern, 0}}}},
      {"stereo",
       {{"max_hamming", {S::kInt, &t.stereo.max_hamming, 0}},
        {"sad_half_window", {S::kInt, &t.stereo.sad_half_window, 1}},
        {"sad_search_px", {S::kInt, &t.stereo.sad_search_px, 1}},
        {"sad_outlier_factor", {S::kFloat, &t.stereo.sad_outlier_factor, 0.01}},
        {"centre_pixel_offset", {S::kBool, &t.stereo.centre_pixel_offset, 0}},
        {"equiangular_fit", {S::kSubPixelFit, &t.stereo.fit, 0}},
        {"far_disparity", {S::kBool, &t.stereo.far_disparity, 0}},
        {"close_depth_baselines", {S::kDouble, &t.stereo.close_depth_baselines, 1}}}},
      {"tracking",
       {{"init_min_stereo", {S::kInt, &t.init_min_stereo, 10}},
        {"last_frame_radius", {S::kFloat, &t.last_frame_radius, 0.5}},
        {"min_last_frame_matches", {S::kInt, &t.min_last_frame_matches, 3}},
        {"motion_model_min_inliers", {S::kInt, &t.motion_model_min_inliers, 0}},
        {"local_map_radius", {S::kFloat, &t.local_map_radius, 0.1}},
        {"lost_radius", {S::kFloat, &t.lost_radius, 0.1}},
        {"predict_through_loss_s", {S::kDouble, &t.predict_through_loss_s, 0}},
        {"restart_after_lost", {S::kInt, &t.restart_after_lost, 0}},
        {"recovery_min_gate_m", {S::kDouble, &t.recovery_min_gate_m, 0}},
        {"recovery_max_accel_mps2", {S::kDouble, &t.recovery_max_accel_mps2, 0}},
        {"min_inliers", {S::kInt, &t.min_inliers, 3}},
        {"min_inliers_after_loss", {S::kInt, &t.min_inliers_after_loss, 3}},
        {"max_local_keyframes", {S::kInt, &t.max_local_keyframes, 1}},
        {"keyframe_max_frames", {S::kInt, &t.keyframe_max_frames, 1}},
        {"keyframe_ref_ratio", {S::kFloat, &t.keyframe_ref_ratio, 0}},
        {"keyframe_ref_min_observers", {S::kInt, &t.keyframe_ref_min_observers, 1}},
        {"keyframe_close_tracked_max", {S::kInt, &t.keyframe_close_tracked_max, 0}},
        {"keyframe_close_untracked_min", {S::kInt, &t.keyframe_close_untracked_min, 0}},
        {"keyframe_max_turn_deg", {S::kDouble, &t.keyframe_max_turn_deg, 0}},
        {"new_points_min", {S::kInt, &t.new_points_min, 0}},
        {"create_far_points", {S::kBool, &t.create_far_points, 0}},
        {"localize_only", {S::kBool, &t.localize_only, 0}},
        {"localize_relocalize_below", {S::kInt, &t.localize_relocalize_below, 0}},
        {"pose_covariance_scale", {S::kDouble, &t.pose_covariance_scale, 0}}}},
      {"recovery",
       {{"rotation_first", {S::kBool, &t.recover_rotation_first, 0}},
        {"rotation_max_angle_deg", {S::kDouble, &t.rotation_search.max_angle_deg, 0.1}},
        {"rotation_min_distance_m", {S::kDouble, &t.rotation_search.min_distance_m, 0}},
        {"rotation_level_slack", {S::kInt, &t.rotation_search.level_slack, 0}},
        {"rotation_max_hamming", {S::kInt, &t.rotation_search.max_hamming, 0}},
        {"rotation_inlier_px", {S::kDouble, &t.rotation_search.inlier_px, 0.1}},
        {"rotation_iterations", {S::kInt, &t.rotation_search.iterations, 1}},
        {"rotation_min_inliers", {S::kInt, &t.rotation_search.min_inliers, 2}},
        {"pose_iterations", {S::kInt, &t.far_pose.iterations, 1}},
        {"pose_chi2", {S::kDouble, &t.far_pose.chi2, 0.1}},
        {"pose_min_inliers", {S::kInt, &t.far_pose.min_inliers, 3}},
        {"pose_max_offset_m", {S::kDouble, &t.far_pose.max_offset_m, 0}},
        {"pose_max_turn_deg", {S::kDouble, &t.far_pose.max_turn_deg, 0}},
        {"reloc_keyframes", {S::kInt, &t.reloc_keyframes, 1}},
        {"reloc_min_matches", {S::kInt, &t.reloc_min_matches, 4}}}},
  };
}

// The back end's sections: local mapping, loop detection and loop closing; and how the offline pipeline
// runs them.
Sections backEndSettings(SlamConfig& c) {
  LocalMapperParams& m = c.mapper;
  LoopDetectorParams& d = c.detector;
  LoopCloserParams& l = c.closer;
  RecognizerOptions& r = c.models;
  using S = Setting;
  return {
      {"mapping",
       {{"covisibility_min", {S::kInt, &m.covisibility_min, 1}},
        {"cull_after_keyframes", {S::kInt, &m.cull_after_keyframes, 1}},
        {"cull_min_observers", {S::kInt, &m.cull_min_observers, 1}},
        {"cull_count", {S::kCullCount, &m.cull_count, 0}},
        {"triangulate", {S::kBool, &m.triangulate, 0}},
        {"triangulate_neighbors", {S::kInt, &m.triangulate_neighbors, 1}},
        {"fuse", {S::kBool, &m.fuse, 0}},
        {"fuse_radius", {S::kFloat, &m.fuse_radius, 0.1}},
        {"local_ba", {S::kBool, &m.local_ba, 0}},
        {"local_ba_max_keyframes", {S::kInt, &m.local_ba_max_keyframes, 1}},
        {"local_ba_yields", {S::kBool, &m.local_ba_yields, 0}},
        {"ba_robust_iterations", {S::kInt, &m.ba.robust_iterations, 1}},
        {"ba_refine_iterations", {S::kInt, &m.ba.refine_iterations, 0}},
        {"cull_keyframes", {S::kBool, &m.cull_keyframes, 0}},
        {"global_ba_after_loop", {S::kBool, &m.global_ba_after_loop, 0}},
        {"global_ba_robust_iterations", {S::kInt, &m.global_ba_robust_iterations, 1}},
        {"global_ba_refine_iterations", {S::kInt, &m.global_ba_refine_iterations, 0}},
        {"redundant_ratio", {S::kFloat, &m.redundant_ratio, 0}}}},
      {"loop_detection",
       {{"max_reference", {S::kInt, &d.max_reference, 1}},
        {"ignore_recent", {S::kInt, &d.ignore_recent, 0}},
        {"consistency", {S::kInt, &d.consistency, 1}},
        {"consistency_gap", {S::kInt, &d.consistency_gap, 0}},
        {"hbow_min_bar", {S::kDouble, &r.hbow_min_bar, 0}},
        {"fabmap_l2_offset", {S::kDouble, &r.fabmap_l2_offset, 0}},
        {"vladpq_shared_slack", {S::kInt, &r.vladpq_shared_slack, 0}},
        {"vlad_reference_rank", {S::kInt, &r.vlad_reference_rank, 1}}}},
      {"loop_closing",
       {{"max_hamming", {S::kInt, &l.verify.max_hamming, 0}},
        {"ratio", {S::kFloat, &l.verify.ratio, 0}},
        {"min_matches", {S::kInt, &l.verify.min_matches, 3}},
        {"match_by_words", {S::kBool, &l.verify.match_by_words, 0}},
        {"ransac_iterations", {S::kInt, &l.verify.ransac.iterations, 1}},
        {"ransac_confidence", {S::kDouble, &l.verify.ransac.confidence, 0}},
        {"ransac_min_inliers", {S::kInt, &l.verify.ransac.min_inliers, 3}},
        {"min_inliers", {S::kInt, &l.verify.min_inliers, 3}},
        {"covisibility_min", {S::kInt, &l.graph.min_covisibility, 1}},
        {"drift_base_m", {S::kDouble, &l.drift_base_m, 0}},
        {"drift_per_m", {S::kDouble, &l.drift_per_m, 0}},
        {"confirm_min_travel_m", {S::kDouble, &l.confirm_min_travel_m, 0}},
        {"hold_keyframes", {S::kInt, &l.hold_keyframes, 1}},
        {"hold_factor", {S::kDouble, &l.hold_factor, 1}},
        {"max_residual_ratio", {S::kDouble, &l.max_residual_ratio, 0}},
        {"min_keyframes_between_loops", {S::kInt, &l.min_keyframes_between_loops, 0}},
        {"reanchor_min_m", {S::kDouble, &l.reanchor_min_m, 0}},
        {"fuse", {S::kBool, &l.fuse, 0}},
        {"resend_corrections_after_updates", {S::kInt, &l.resend_corrections_after_updates, 1}}}},
      {"pipeline", {{"wait_for_mapping_ms", {S::kDouble, &c.pipeline.wait_for_mapping_ms, 0}}}},
  };
}

// Every section and key of a settings file, with where each value goes in `c`.
Sections settingsOf(SlamConfig& c) {
  Sections all = trackingSettings(c.tracker);
  all.merge(backEndSettings(c));
  return all;
}

double valueOf(const Setting& s) {
  switch (s.kind) {
    case Setting::kInt:
      return *static_cast<int*>(s.ptr);
    case Setting::kFloat:
      return *static_cast<float*>(s.ptr);
    case Setting::kDouble:
      return *static_cast<double*>(s.ptr);
    case Setting::kBool:
      return *static_cast<bool*>(s.ptr) ? 1 : 0;
    case Setting::kSubPixelFit:
      return *static_cast<StereoMatchParams::SubPixelFit*>(s.ptr) ==
             StereoMatchParams::SubPixelFit::kEquiangular;
    case Setting::kPattern:
      return *static_cast<BriefPatternKind*>(s.ptr) == BriefPatternKind::kOrbLearned;
    case Setting::kCullCount:
      return static_cast<int>(*static_cast<LocalMapperParams::CullCount*>(s.ptr));
  }
  return 0;
}

// OpenCV's YAML reader wraps an integer literal beyond 32 bits silently (99999999999 reads as 1215752191),
// so whole numbers are checked on the file's text before it is parsed.
void checkIntegerLiterals(const std::string& path) {
  std::ifstream in(path);
  std::string line, section;
  while (std::getline(in, line)) {
    const std::string code = line.substr(0, line.find('#'));
    const auto colon = code.find(':');
    if (colon == std::string::npos || code.empty() || code[0] == '%') continue;
    const auto first = code.find_first_not_of(" \t");
    std::string key = code.substr(first, colon - first);
    while (!key.empty() && key.back() == ' ') key.pop_back();
    std::string value = code.substr(colon + 1);
    value.erase(0, value.find_first_not_of(" \t"));
    while (!value.empty() && (value.back() == ' ' || value.back() == '\t' || value.back() == '\r'))
      value.pop_back();
    if (first == 0) {
      section = key;
      continue;
    }
    size_t i = (!value.empty() && (value[0] == '-' || value[0] == '+')) ? 1 : 0;
    if (i == value.size() || value.find_first_not_of("0123456789", i) != std::string::npos) continue;
    if (std::stold(value) > std::numeric_limits<int>::max() ||
        std::stold(value) < std::numeric_limits<int>::min()) {
      throw ConfigError(path + ": " + section + "." + key + " = " + value + " is out of range (at most " +
                        std::to_string(std::numeric_limits<int>::max()) + ")");
    }
  }
}

// How many values a setting that picks one of several choices takes (0, 1, ...); 0 for a plain number.
int choicesOf(Setting::Kind kind) {
  switch (kind) {
    case Setting::kBool:
    case Setting::kSubPixelFit:
    case Setting::kPattern:
      return 2;
    case Setting::kCullCount:
      return 3;
    case Setting::kInt:
    case Setting::kFloat:
    case Setting::kDouble:
      return 0;  // numbers, not choices
  }
  return 0;
}

// "0 or 1", "0, 1 or 2", ...
std::string choiceList(int choices) {
  std::string list;
  for (int i = 0; i + 1 < choices; ++i) list += (i > 0 ? ", " : "") + std::to_string(i);
  return list + " or " + std::to_string(choices - 1);
}

// One setting from its YAML value, checked against its kind and range; `where` names it in the messages.
void setFromYaml(const Setting& s, const cv::FileNode& v, const std::string& where) {
  if (!v.isInt() && !v.isReal()) throw ConfigError(where + " must be a number");
  const double x = v.real();
  if (!std::isfinite(x) || x < s.min) {
    throw ConfigError(where + " = " + std::to_string(x) + " is out of range (at least " +
                      std::to_string(s.min) + ")");
  }
  const int choices = choicesOf(s.kind);
  if ((s.kind == Setting::kInt || choices > 0) && x != std::floor(x))
    throw ConfigError(where + " must be a whole number");
  if (s.kind == Setting::kInt && x > std::numeric_limits<int>::max()) {
    throw ConfigError(where + " = " + std::to_string(x) + " is out of range (at most " +
                      std::to_string(std::numeric_limits<int>::max()) + ")");
  }
  if (choices > 0 && x >= choices) throw ConfigError(where + " must be " + choiceList(choices));
  switch (s.kind) {
    case Setting::kInt:
      *static_cast<int*>(s.ptr) = static_cast<int>(x);
      break;
    case Setting::kFloat:
      *static_cast<float*>(s.ptr) = static_cast<float>(x);
      break;
    case Setting::kDouble:
      *static_cast<double*>(s.ptr) = x;
      break;
    case Setting::kBool:
      *static_cast<bool*>(s.ptr) = x != 0;
      break;
    case Setting::kSubPixelFit:
      *static_cast<StereoMatchParams::SubPixelFit*>(s.ptr) =
          x != 0 ? StereoMatchParams::SubPixelFit::kEquiangular : StereoMatchParams::SubPixelFit::kParabola;
      break;
    case Setting::kPattern:
      *static_cast<BriefPatternKind*>(s.ptr) =
          x != 0 ? BriefPatternKind::kOrbLearned : BriefPatternKind::kGaussian;
      break;
    case Setting::kCullCount:
      *static_cast<LocalMapperParams::CullCount*>(s.ptr) =
          static_cast<LocalMapperParams::CullCount>(static_cast<int>(x));
      break;
  }
}

}  // namespace

SlamConfig loadSlamConfig(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw ConfigError(path + ": no such file");
  checkIntegerLiterals(path);
  cv::FileStorage fs;
  try {
    if (!fs.open(path, cv::FileStorage::READ | cv::FileStorage::FORMAT_YAML))
      throw ConfigError(path + ": cannot be read as YAML");
  } catch (const cv::Exception& e) {
    throw ConfigError(path + ": not valid YAML (" + e.msg + ")");
  }
  SlamConfig c;
  auto settings = settingsOf(c);
  const cv::FileNode root = fs.root();
  if (!root.isMap()) {
    throw ConfigError(
        path +
        ": expected sections (orb, stereo, tracking, recovery, mapping, loop_detection, loop_closing, "
        "pipeline)");
  }
  for (const std::string& section : root.keys()) {
    auto sec = settings.find(section);
    if (sec == settings.end()) {
      std::string known;
      for (const auto& [name, _] : settings) known += (known.empty() ? "" : ", ") + name;
      throw ConfigError(path + ": unknown section '" + section + "' (known: " + known + ")");
    }
    const cv::FileNode node = root[section];
    if (!node.isMap()) throw ConfigError(path + ": section '" + section + "' must hold key: value lines");
    for (const std::string& key : node.keys()) {
      auto it = sec->second.find(key);
      if (it == sec->second.end()) {
        std::string known;
        for (const auto& [name, _] : sec->second) known += (known.empty() ? "" : ", ") + name;
        throw ConfigError(path + ": unknown key '" + section + "." + key + "' (known in " + section + ": " +
                          known + ")");
      }
      setFromYaml(it->second, node[key], path + ": " + section + "." + key);
    }
  }
  if (c.tracker.orb.min_fast > c.tracker.orb.ini_fast)
    throw ConfigError(path + ": orb.min_fast must not exceed orb.ini_fast");
  c.mapper.stereo = c.tracker.stereo;
  return c;
}

std::string describe(const SlamConfig& c0) {
  SlamConfig c = c0;
  std::ostringstream out;
  for (const auto& [section, keys] : settingsOf(c))
    for (const auto& [key, s] : keys) out << section << "." << key << ": " << valueOf(s) << "\n";
  return out.str();
}

}  // namespace binloop
