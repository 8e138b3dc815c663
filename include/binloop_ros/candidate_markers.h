#pragma once
// The loop detector's view, live in rviz: for the latest query keyframe, a line to each candidate it
// proposed (best first; the accepted one green, the others from orange to grey by rank) and a label with the
// model, its status and the best score. Each query replaces the previous one's markers. Keyframe positions
// are those the detector was given (before later loop corrections).
#include <binloop/LoopCandidates.h>
#include <visualization_msgs/MarkerArray.h>

#include <Eigen/Core>
#include <string>
#include <unordered_map>

namespace binloop_ros {

class CandidateMarkers {
 public:
  /// Remembers where keyframe `id` is (in `frame`, the frame of the keyframes the detector receives).
  void keyframe(uint64_t id, const Eigen::Vector3d& position, const std::string& frame);
  /// Markers for one query; a candidate whose keyframe is unknown gets no line.
  visualization_msgs::MarkerArray markers(const binloop::LoopCandidates& q) const;

  static constexpr size_t kMaxLines = 5;

 private:
  std::unordered_map<uint64_t, Eigen::Vector3d> positions_;
  std::string frame_;
};

}  // namespace binloop_ros
