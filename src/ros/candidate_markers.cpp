#include "binloop_ros/candidate_markers.h"

#include <cstdio>

#include "binloop_ros/msg_conversion.h"

namespace binloop_ros {

namespace {

std_msgs::ColorRGBA colour(float r, float g, float b, float a = 1.f) {
  std_msgs::ColorRGBA c;
  c.r = r;
  c.g = g;
  c.b = b;
  c.a = a;
  return c;
}

}  // namespace

void CandidateMarkers::keyframe(uint64_t id, const Eigen::Vector3d& position, const std::string& frame) {
  positions_[id] = position;
  frame_ = frame;
}

visualization_msgs::MarkerArray CandidateMarkers::markers(const binloop::LoopCandidates& q) const {
  visualization_msgs::Marker lines;
  lines.header.frame_id = frame_;
  lines.header.stamp = q.header.stamp;
  lines.ns = "loop_candidates";
  lines.id = 0;
  lines.type = visualization_msgs::Marker::LINE_LIST;
  lines.action = visualization_msgs::Marker::ADD;
  lines.pose.orientation.w = 1;
  lines.scale.x = 0.3;
  visualization_msgs::Marker label = lines;
  label.id = 1;
  label.type = visualization_msgs::Marker::TEXT_VIEW_FACING;
  label.scale.x = 0;
  label.scale.z = 2.0;
  label.color = colour(1, 1, 1);

  const auto query = positions_.find(q.query);
  if (query != positions_.end()) {
    label.pose.position =
        toPoint(query->second + Eigen::Vector3d(0, -3, 0));  // above it (y points down in slam)
    for (size_t i = 0; i < q.candidates.size() && i < kMaxLines; ++i) {
      const auto c = positions_.find(q.candidates[i].id);
      if (c == positions_.end()) continue;
      const bool accepted = q.candidates[i].id == q.accepted;
      const float fade = 1.f - 0.15f * static_cast<float>(i);
      const std_msgs::ColorRGBA col =
          accepted ? colour(0.1f, 0.9f, 0.1f) : colour(fade, 0.55f * fade, 0.1f, 0.8f);
      lines.points.push_back(toPoint(query->second));
      lines.points.push_back(toPoint(c->second));
      lines.colors.push_back(col);
      lines.colors.push_back(col);
    }
  }
  char best[64] = "";
  if (!q.candidates.empty()) std::snprintf(best, sizeof best, ", best %.3f", q.candidates.front().score);
  label.text = q.model + ": " + q.status + " (" + std::to_string(q.candidates.size()) + " candidates" + best +
               (q.accepted ? ", accepted" : "") + ")";
  // An empty line list or a label without a place: delete the previous query's instead of drawing nothing.
  if (lines.points.empty()) lines.action = visualization_msgs::Marker::DELETE;
  if (query == positions_.end()) label.action = visualization_msgs::Marker::DELETE;
  visualization_msgs::MarkerArray out;
  out.markers = {lines, label};
  return out;
}

}  // namespace binloop_ros
