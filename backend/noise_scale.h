// How far a graph's information matrices understate its noise, measured on
// short cycles of the graph itself.
//
// Every robust method decides at a chi2 gate in each constraint's own
// information (docs/backend.md). That is right when the information is
// right or conservative; a file whose information claims far less noise
// than its measurements carry (chi2 many times its degrees of freedom at the
// optimum) has almost every true closure beyond the gate. The cycles here
// show it without knowing which closures are true.
#ifndef CATGRAPH_BACKEND_NOISE_SCALE_H_
#define CATGRAPH_BACKEND_NOISE_SCALE_H_

#include <set>

#include "backend/graph/pose_graph.h"

namespace catgraph {

struct NoiseScaleOptions {
  // A partner closure's ends lie at most this many poses from the closure's
  // (odometry chains of at most this length close the cycle); >= 1.
  int window = 5;
  // Cycles solved at most (spread evenly over the closures); >= 1.
  int max_cycles = 400;
  // Below this many cycles there is no estimate (scale 1); >= 1.
  int min_cycles = 20;
  // The quantile of the cycles' chi2 compared with chi2(dof)'s: a low one,
  // so that up to three quarters of the cycles may hold a false closure;
  // (0, 1).
  double quantile = 0.25;
  // A second, higher quantile: with `quantile`'s, the shape of the cycles'
  // distribution (both scales agree when the noise is Gaussian with one
  // variance); (quantile, 1).
  double upper_quantile = 0.9;
};

// Throws std::invalid_argument when a field is out of range.
void Validate(const NoiseScaleOptions& options);

struct NoiseScaleEstimate {
  // Q(cycle chi2) / Q(chi2(dof)) at the quantile: about 1 when the
  // information is right, below 1 when it is conservative, k when the
  // noise's variance is k times what it states. 1 without an estimate.
  double scale = 1.0;
  // The same ratio at the upper quantile: about `scale` for Gaussian noise,
  // larger when the noise has heavier tails (or false closures). 1 without
  // an estimate.
  double upper_scale = 1.0;
  int cycles = 0;  // cycles solved
};

// A short cycle is a closure (a, b), a partner closure (a', b') with
// 0 < a' - a <= window and |b' - b| <= window, and the odometry chains
// a..a' and b..b' (consecutive ids, kind odometry). Each cycle's chi2 is that
// of the plain least-squares solution of its own small graph (g2o's cost,
// a fixed), which for true measurements with right information follows
// chi2(3) in 2D and chi2(6) in 3D. Closures in `excluded` (a robust solve's
// rejected ones) belong to no cycle. Deterministic. Validates `options`.
NoiseScaleEstimate EstimateNoiseScale(const PoseGraph2& graph, const NoiseScaleOptions& options = {},
                                      const std::set<ClosureId>& excluded = {});
NoiseScaleEstimate EstimateNoiseScale(const PoseGraph3& graph, const NoiseScaleOptions& options = {},
                                      const std::set<ClosureId>& excluded = {});

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_NOISE_SCALE_H_
