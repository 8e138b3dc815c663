#pragma once
// Matching map points to a frame's keypoints by projecting them with a predicted pose (ORB-SLAM2's
// SearchByProjection): each point only competes for the keypoints near where it should appear, at the
// pyramid level its distance predicts, so a frame is matched in about a millisecond without any global
// descriptor search.
#include <functional>
#include <vector>

#include "binloop/map/point_projection.h"
#include "binloop/messages/map_state.h"
#include "binloop/tracking/frame.h"

namespace binloop {

struct ProjectionParams {
  int max_hamming = 100;       // ORB-SLAM2's TH_HIGH
  float ratio = 0.8f;          // best vs second best when both are at the same level (local map search)
  bool check_rotation = true;  // last-frame search: keep matches whose angle change is among the 3 commonest
};

/// Matches points to the frame's unmatched keypoints within th * (2.5 or 4 by viewing angle) * level scale
/// of their projection; returns the number of new matches.
int matchProjectedPoints(Frame& f, const std::vector<ProjectedPoint>& pts, const ScalePyramid& s, float th,
                         const ProjectionParams& p = {});

/// The last frame's matched points into the current one, predicted with `cur.T_w_c`; search radius th times
/// the last keypoint's level scale, levels restricted by the direction of motion. `lookup` gives a map point
/// by id or nullptr. Returns the number of matches.
int matchFromLastFrame(Frame& cur, const Frame& last,
                       const std::function<const msg::MapPoint*(MapPointId)>& lookup, const StereoCamera& cam,
                       const ScalePyramid& s, float th, const ProjectionParams& p = {});

/// Without a pose prediction (the frame after the first keyframe, or after a failure): every matched point
/// of `last` against every keypoint of `cur` by descriptor (best below max_hamming_strict and clearly better
/// than the second, ratio 0.7), then the rotation check. ORB-SLAM2 narrows this with BoW nodes; 2000 x 2000
/// Hamming distances take about 3 ms, which a once-in-a-while fallback can pay.
int matchByDescriptor(Frame& cur, const Frame& last,
                      const std::function<const msg::MapPoint*(MapPointId)>& lookup,
                      int max_hamming_strict = 50, float ratio = 0.7f);

}  // namespace binloop
