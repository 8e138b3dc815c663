#pragma once
// A synthetic street world in KITTI's world frame (camera 0 at frame 0: x right, y down, z forward).
// Everything visible is a textured planar quad anchored in the world, so a place looks the same
// (from a new viewpoint) every time the route comes back to it; the ground is an analytic surface
// whose material comes from a map of distance to the route (road, pavement, verge).
#include <Eigen/Core>
#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <vector>

#include "binloop/sim/texture_bank.h"
#include "binloop/types/pose.h"

namespace binloop::sim {

struct Quad {
  enum Shape : uint8_t { kRect = 0, kTree = 1 };  // kTree: crown-and-trunk cut-out (alpha by shape)
  Eigen::Vector3f o;                              // corner at (u, v) = (0, 0)
  Eigen::Vector3f a, b;                           // unit axes of u and v (metres)
  float lu = 0, lv = 0;                           // extents along a and b (metres)
  int texture = 0;                                // index into TextureBank::textures
  float texels_per_m = 50;                        // texture scale
  float off_u = 0, off_v = 0;  // texel offset (different places cut different parts of a texture)
  float shade = 1;             // brightness factor (orientation to the sun)
  Shape shape = kRect;
  float max_distance = 200;  // not drawn farther than this (metres, from the camera)
};

struct WorldParams {
  double camera_height_m = 1.65;   // KITTI's camera above the road
  double road_half_width_m = 5.0;  // route to kerb (parked cars stand inside it)
  double pavement_width_m = 2.5;
  double setback_min_m = 7.0, setback_max_m = 15.0;  // route to façade
  double facade_len_min_m = 8.0, facade_len_max_m = 24.0;
  double height_min_m = 6.0, height_max_m = 20.0;
  double gap_probability = 0.15;    // chance of a gap (alley, lot) after a façade
  double repeat_probability = 0.1;  // chance a façade copies an earlier one exactly (perceptual aliasing)
  double car_probability = 0.35, tree_probability = 0.3, pole_spacing_m = 30.0;
  double clearance_m = 5.0;  // nothing but ground within this distance of any route point
  bool populate = true;      // false: ground only (tests then add their own quads)
  /// The ground texture repeats every 8 m (512 texels at 64 per metre), so a camera displaced by a multiple
  /// of 8 m along the grid sees the same road: a relocalisation can lock on to it. True: a second, rotated
  /// layer of incommensurate period is blended in, and the road never repeats within a route. Off by default
  /// so that renders made before it stay as they were.
  bool aperiodic_ground = false;
  /// By default the ground is a plane fitted anew for each camera: camera_height_m under it, tilted with the
  /// route's grade over +-20 m. It follows the camera, so it is not the same surface from one frame to the
  /// next (in rendered 06's first U-turn it turns by 0.15-0.2 degrees a frame, which moves a road point 10 m
  /// ahead by about 2 px) nor for the two cameras of one pair. True: one surface for the whole world, a
  /// height field smoothed from the route's heights, as a real road is. Off by default so that renders made
  /// before it stay as they were (the peer results binloop is compared with were made on those).
  bool rigid_ground = false;
};

class World {
 public:
  /// Builds the world around `route` (ground-truth T_w_c per frame) with textures from `bank`.
  static World build(const std::vector<Pose3>& route_T_w_c, TextureBank bank, const WorldParams& params,
                     uint64_t seed);

  /// Adds quads (e.g. a test's known façade) after building.
  void addQuads(const std::vector<Quad>& quads);

  const TextureBank& bank() const { return bank_; }
  const std::vector<Quad>& quads() const { return quads_; }
  /// Indices of quads whose anchor lies within `radius` of (x, z).
  void quadsNear(double x, double z, double radius, std::vector<int>* out) const;
  /// Ground under the camera at pose T_w_c: plane n·p = d (n points down, world y down).
  void groundPlane(const Pose3& T_w_c, Eigen::Vector3d* n, double* d) const;
  /// With `rigid_ground`: the road surface's world y at (x, z) (y down) and its slopes dy/dx and dy/dz
  /// (bilinear between 2 m grid nodes).
  double groundY(double x, double z, double* dy_dx = nullptr, double* dy_dz = nullptr) const;
  bool rigidGround() const { return !ground_y_.empty(); }
  /// Ground texture index at world (x, z).
  int groundMaterial(double x, double z) const;
  const WorldParams& params() const { return params_; }

 private:
  TextureBank bank_;
  WorldParams params_;
  std::vector<Quad> quads_;
  std::vector<Eigen::Vector3d> route_;  // resampled route positions (every ~2 m)
  std::vector<Eigen::Vector3d> route_dir_;
  // 2-D grid of quad indices by anchor cell
  double cell_ = 20, gx0_ = 0, gz0_ = 0;
  int gw_ = 0, gh_ = 0;
  std::vector<std::vector<int>> grid_;
  double max_quad_extent_ = 0;
  // ground material map (0.5 m cells)
  double mcell_ = 0.5, mx0_ = 0, mz0_ = 0;
  cv::Mat material_;  // CV_8U: 0 road, 1 pavement, 2 verge
  // route-sample grid for nearest-route queries
  std::vector<std::vector<int>> route_grid_;
  int rgw_ = 0, rgh_ = 0;  // route grid size (cells)
  // rigid ground: world y of the road surface at grid nodes (hx0_ + i * hcell_, hz0_ + j * hcell_)
  double hcell_ = 2.0, hx0_ = 0, hz0_ = 0;
  int hw_ = 0, hh_ = 0;
  std::vector<float> ground_y_;
  int nearestRouteSample(double x, double z) const;
  void indexQuads();
  void buildGroundHeights(double width_m, double depth_m);  // over the quad grid's extent, from its origin
};

}  // namespace binloop::sim
