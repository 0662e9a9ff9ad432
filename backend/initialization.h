// Initial guesses for pose graphs without (or with poor) initial poses.
#ifndef CATGRAPH_BACKEND_INITIALIZATION_H_
#define CATGRAPH_BACKEND_INITIALIZATION_H_

#include "backend/graph/pose_graph.h"

namespace catgraph {

// Chains measurements along a spanning tree, odometry first: from each
// component's lowest id (at the identity, or its own pose if it has one),
// breadth-first over odometry constraints, then over all constraints for what
// odometry does not reach. Only vertices without a pose are set unless
// `overwrite` is true.
void InitializeBySpanningTree(PoseGraph2& graph, bool overwrite = false);
void InitializeBySpanningTree(PoseGraph3& graph, bool overwrite = false);

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_INITIALIZATION_H_
