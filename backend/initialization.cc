#include "backend/initialization.h"

#include <deque>
#include <unordered_map>
#include <vector>

namespace catgraph {
namespace {

template <typename PoseT>
void Initialize(PoseGraph<PoseT>& graph, bool overwrite) {
  struct Arc {
    PoseId other;
    PoseT T_self_other;
    bool odometry;
  };
  std::unordered_map<PoseId, std::vector<Arc>> arcs;
  for (const auto& c : graph.constraints) {
    const bool odometry = c.kind == ClosureKind::kOdometry;
    arcs[c.from].push_back({c.to, c.measurement.mean, odometry});
    arcs[c.to].push_back({c.from, c.measurement.mean.Inverse(), odometry});
  }
  std::unordered_map<PoseId, PoseT> placed;
  // Breadth-first from `frontier` over arcs accepted by `use`.
  auto grow = [&](std::deque<PoseId> frontier, bool odometry_only) {
    while (!frontier.empty()) {
      const PoseId id = frontier.front();
      frontier.pop_front();
      for (const Arc& arc : arcs[id]) {
        if ((odometry_only && !arc.odometry) || placed.contains(arc.other)) continue;
        placed.emplace(arc.other, placed.at(id) * arc.T_self_other);
        frontier.push_back(arc.other);
      }
    }
  };
  for (const auto& [root, vertex] : graph.vertices) {  // ascending ids
    if (placed.contains(root)) continue;
    placed.emplace(root, (!overwrite && vertex.pose) ? *vertex.pose : PoseT::Identity());
    std::deque<PoseId> component{root};
    grow(component, true);
    std::deque<PoseId> all;
    for (const auto& [id, pose] : placed) all.push_back(id);
    grow(all, false);
  }
  for (auto& [id, vertex] : graph.vertices) {
    if (overwrite || !vertex.pose) vertex.pose = placed.at(id);
  }
}

}  // namespace

void InitializeBySpanningTree(PoseGraph2& graph, bool overwrite) { Initialize(graph, overwrite); }
void InitializeBySpanningTree(PoseGraph3& graph, bool overwrite) { Initialize(graph, overwrite); }

}  // namespace catgraph
