// False loop closures for robust-back-end experiments, following Vertigo's
// generator as re-described in ../shared/docs/robust-backend-notes.md §2
// (the "random" policy, groups of one): v1, v2 uniform on {0 ... N-2},
// redrawn while equal, sorted, v2 = v1 + 2 if they are consecutive; the
// measurement dx, dy ~ N(0, 0.3 m), dtheta ~ N(0, 10 deg); the information
// copied from the first loop closure of the graph (identity if none).
// Injected closures have kind kInjected and fresh closure ids.
#ifndef CATGRAPH_SIMULATION_OUTLIER_INJECTION_H_
#define CATGRAPH_SIMULATION_OUTLIER_INJECTION_H_

#include <cstdint>
#include <vector>

#include "backend/graph/pose_graph.h"

namespace catgraph {

// Returns the ids of the injected closures. Poses are numbered 0 ... N-1 in
// the graph's id order. Throws std::invalid_argument for fewer than 4 poses.
std::vector<ClosureId> InjectRandomOutliers(PoseGraph2& graph, int count, std::uint64_t seed);

}  // namespace catgraph

#endif  // CATGRAPH_SIMULATION_OUTLIER_INJECTION_H_
