#pragma once
// Where a map point should appear in a camera (ORB-SLAM2's isInFrustum), and which matches agree on the
// rotation between two views: shared by tracking (its projection search, tracking/projection_search.h) and
// local mapping (point fusion, epipolar matching).
#include <cstdint>
#include <vector>

#include "binloop/map/scale_pyramid.h"
#include "binloop/messages/map_state.h"
#include "binloop/types/pose.h"
#include "binloop/types/stereo_camera.h"

namespace binloop {

/// A map point predicted to be visible in a frame: where, and at which pyramid level.
struct ProjectedPoint {
  const msg::MapPoint* point = nullptr;
  float u = 0, v = 0, u_right = 0;
  int level = 0;
  float view_cos = 1;  // between the viewing ray and the point's mean viewing direction
};

/// ORB-SLAM2's isInFrustum: in front of the camera, inside the image, within the point's distance range
/// (with 20 % slack) and seen less than 60 degrees off its mean direction.
bool projectIntoFrame(const msg::MapPoint& p, const Pose3& T_c_w, const StereoCamera& cam,
                      const ScalePyramid& s, ProjectedPoint* out);

/// Indices of the matches to keep: those whose angle difference falls in the three most populated of 30
/// bins (a bin below 10 % of the largest is dropped), as ORB-SLAM2 does.
std::vector<uint8_t> rotationConsistent(const std::vector<float>& angle_diff_deg);

}  // namespace binloop
