#include "frontend/trajectory_graph.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <stdexcept>
#include <string>
#include <tuple>

namespace catgraph {

int TrajectoryGraph::AddNode(int frame, double time_s, double path_length_m, WordSet words) {
  GraphNode node;
  node.frame = frame;
  node.time_s = time_s;
  node.path_length_m = path_length_m;
  node.words = std::move(words);
  nodes_.push_back(std::move(node));
  return static_cast<int>(nodes_.size()) - 1;
}

int TrajectoryGraph::AddEdge(int from, int to, const Pose2& u, EdgeType type) {
  const int n = static_cast<int>(nodes_.size());
  if (from < 0 || from >= n || to < 0 || to >= n || from == to) {
    throw std::invalid_argument("trajectory graph: edge " + std::to_string(from) + " -> " +
                                std::to_string(to) + " needs two distinct existing nodes");
  }
  const int id = static_cast<int>(edges_.size());
  edges_.push_back({from, to, u, type, u.translation().norm()});
  nodes_[static_cast<std::size_t>(from)].edges.push_back(id);
  nodes_[static_cast<std::size_t>(to)].edges.push_back(id);
  return id;
}

Pose2 LocalGraph::PointPose(const TrajectoryGraph& graph, int edge, double alpha) const {
  // Along the segment between the two node poses, as the projection sees it
  // (with loops, the end may have been reached by another path than e).
  const GraphEdge& e = graph.edge(edge);
  return Interpolate(pose.at(e.from), pose.at(e.to), alpha);
}

LocalGraph BuildLocalGraph(const TrajectoryGraph& graph, int anchor, double radius_m,
                           const std::function<bool(int)>& eligible) {
  LocalGraph local;
  using Entry = std::tuple<double, int, Pose2>;  // path length, node, pose
  auto later = [](const Entry& a, const Entry& b) { return std::get<0>(a) > std::get<0>(b); };
  std::priority_queue<Entry, std::vector<Entry>, decltype(later)> fringe(later);
  fringe.emplace(0.0, anchor, Pose2());
  while (!fringe.empty()) {
    const auto [g, n, pose] = fringe.top();
    fringe.pop();
    if (!local.pose.emplace(n, pose).second) continue;  // the first arrival is the shortest
    for (const int id : graph.node(n).edges) {
      const GraphEdge& e = graph.edge(id);
      const int m = e.from == n ? e.to : e.from;
      if (local.Contains(m) || (eligible && !eligible(m))) continue;
      const Pose2 next = e.from == n ? pose * e.u : pose * e.u.Inverse();
      if (next.translation().norm() > radius_m) continue;
      fringe.emplace(g + e.length_m, m, next);
    }
  }
  for (const auto& [n, pose] : local.pose) {
    for (const int id : graph.node(n).edges) {
      const GraphEdge& e = graph.edge(id);
      // Each edge once: from its start node.
      if (e.from == n && local.Contains(e.to)) local.edges.push_back(id);
    }
  }
  std::sort(local.edges.begin(), local.edges.end());
  return local;
}

std::optional<Projection> ProjectOntoLocalGraph(const TrajectoryGraph& graph, const LocalGraph& local,
                                                const Pose2& y) {
  std::optional<Projection> best;
  const Eigen::Vector2d p = y.translation();
  for (const int id : local.edges) {
    const GraphEdge& e = graph.edge(id);
    const Pose2& a = local.pose.at(e.from);
    const Pose2& b = local.pose.at(e.to);
    const Eigen::Vector2d ab = b.translation() - a.translation();
    const double len2 = ab.squaredNorm();
    if (len2 < 1e-12) continue;
    const double t = std::clamp((p - a.translation()).dot(ab) / len2, 0.0, 1.0);
    const Eigen::Vector2d q = a.translation() + t * ab;
    const double d = (p - q).norm();
    if (!best || d < best->distance_m) {
      // The path heading along a straight segment between the two node poses.
      const double heading = a.theta() + t * WrapAngle(b.theta() - a.theta());
      best = Projection{id, t, Pose2(q.x(), q.y(), heading), d};
    }
  }
  return best;
}

}  // namespace catgraph
