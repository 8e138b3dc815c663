// The live loop view: lines from the query keyframe to its candidates, the accepted one green, and a label.
#include "binloop_ros/candidate_markers.h"

#include <gtest/gtest.h>

using binloop_ros::CandidateMarkers;

namespace {

binloop::LoopCandidate candidate(uint64_t id, double score) {
  binloop::LoopCandidate c;
  c.id = id;
  c.score = score;
  return c;
}

}  // namespace

TEST(CandidateMarkers, LinesGoFromTheQueryToEachKnownCandidateAndTheAcceptedOneIsGreen) {
  CandidateMarkers view;
  for (uint64_t id = 1; id <= 8; ++id) view.keyframe(id, Eigen::Vector3d(0, 0, 10.0 * id), "slam");
  binloop::LoopCandidates q;
  q.query = 8;
  q.model = "hmvlad";
  q.status = "found";
  q.candidates = {candidate(2, 0.91), candidate(99, 0.5), candidate(3, 0.42)};  // 99: never seen
  q.accepted = 2;
  const auto m = view.markers(q);
  ASSERT_EQ(m.markers.size(), 2u);
  const auto& lines = m.markers[0];
  EXPECT_EQ(lines.header.frame_id, "slam");
  EXPECT_EQ(lines.action, visualization_msgs::Marker::ADD);
  ASSERT_EQ(lines.points.size(), 4u);  // two known candidates, two points each
  EXPECT_DOUBLE_EQ(lines.points[0].z, 80);
  EXPECT_DOUBLE_EQ(lines.points[1].z, 20);
  EXPECT_DOUBLE_EQ(lines.points[3].z, 30);
  EXPECT_GT(lines.colors[0].g, 0.8f);               // accepted: green
  EXPECT_LT(lines.colors[2].g, lines.colors[2].r);  // the other: orange
  EXPECT_EQ(m.markers[1].text, "hmvlad: found (3 candidates, best 0.910, accepted)");

  // A query with nothing to show deletes the previous lines instead of leaving them.
  q.candidates.clear();
  q.accepted = 0;
  q.status = "below_reference";
  const auto empty = view.markers(q);
  EXPECT_EQ(empty.markers[0].action, visualization_msgs::Marker::DELETE);
  EXPECT_EQ(empty.markers[1].text, "hmvlad: below_reference (0 candidates)");
}
