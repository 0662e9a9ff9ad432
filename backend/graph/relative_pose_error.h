// g2o's error of a relative-pose measurement and its chi2, at given poses
// (docs/backend.md, Residuals): the optimiser's chi2 and the evaluation's
// chi2 at the true poses. The Ceres functors compute the same error on raw
// parameter blocks for automatic differentiation (cost_functors.h); a test
// checks that the two agree.
#ifndef CATGRAPH_BACKEND_GRAPH_RELATIVE_POSE_ERROR_H_
#define CATGRAPH_BACKEND_GRAPH_RELATIVE_POSE_ERROR_H_

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "backend/graph/pose2.h"
#include "backend/graph/pose3.h"
#include "backend/graph/pose_graph.h"

namespace catgraph {

// e = [t; θ] of Z⁻¹ X_from⁻¹ X_to, θ wrapped.
inline Eigen::Vector3d RelativePoseError(const Pose2& from, const Pose2& to, const Pose2& z) {
  return z.Between(from.Between(to)).ToVector();
}

// e = [t; vec(q)] of Z⁻¹ X_from⁻¹ X_to, with q's scalar part made >= 0.
inline Eigen::Matrix<double, 6, 1> RelativePoseError(const Pose3& from, const Pose3& to, const Pose3& z) {
  const Pose3 d = z.Between(from.Between(to));
  Eigen::Quaterniond q = d.rotation();
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();
  Eigen::Matrix<double, 6, 1> e;
  e << d.translation(), q.vec();
  return e;
}

// eᵀ Ω e.
template <typename PoseT>
double RelativePoseChi2(const PoseT& from, const PoseT& to, const RelativePoseMeasurement<PoseT>& z) {
  const auto e = RelativePoseError(from, to, z.mean);
  return e.dot(z.information * e);
}

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_GRAPH_RELATIVE_POSE_ERROR_H_
