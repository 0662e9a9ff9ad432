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

// Chordal (rotation-first) initialisation (Carlone et al., ICRA 2015):
// 1. rotations: the linear least-squares solution of R_j = R_i R_ij over all
//    constraints, each R relaxed to a free d x d matrix and weighted by the
//    rotational precision kappa, then projected onto SO(d) by SVD;
// 2. translations: the linear least-squares solution of
//    t_j - t_i = R_i t_ij with those rotations, weighted by tau.
// kappa and tau are SE-Sync's (robust-backend-notes.md §3). Every pose is
// overwritten; the lowest id keeps its pose (identity if it has none). It
// escapes the basins that trap a local solver started from chained odometry
// whose heading errors have wound the map up. Throws std::invalid_argument for a disconnected graph.
void InitializeChordal(PoseGraph2& graph);
void InitializeChordal(PoseGraph3& graph);

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_INITIALIZATION_H_
