// Exact (or toleranced) equality of two pose graphs, for round-trip tests.
#ifndef CATGRAPH_TESTS_IO_GRAPH_EQUALITY_H_
#define CATGRAPH_TESTS_IO_GRAPH_EQUALITY_H_

#include <variant>

#include "tests/catch.h"

#include "backend/graph/pose_graph.h"
#include "tests/test_support.h"

namespace catgraph::testing {

inline bool PosesEqual(const Pose2& a, const Pose2& b, double tol) {
  return tol == 0.0 ? a.ToVector() == b.ToVector() : ApproxEqual(a, b, tol);
}
inline bool PosesEqual(const Pose3& a, const Pose3& b, double tol) {
  return ApproxEqual(a, b, tol);
}

// tol == 0 demands bit-identical 2D values; 3D always allows `tol` because a
// quaternion is renormalised on reading.
template <typename PoseT>
bool GraphsEqual(const PoseGraph<PoseT>& a, const PoseGraph<PoseT>& b, double tol) {
  const double pose_tol = PoseGraph<PoseT>::kDimension == 3 ? std::max(tol, 1e-12) : tol;
  if (a.vertices.size() != b.vertices.size()) { UNSCOPED_INFO("vertex count"); return false; }
  for (const auto& [id, v] : a.vertices) {
    auto it = b.vertices.find(id);
    if (it == b.vertices.end() || it->second.fixed != v.fixed ||
        it->second.pose.has_value() != v.pose.has_value() ||
        (v.pose && !PosesEqual(*v.pose, *it->second.pose, pose_tol))) {
      UNSCOPED_INFO("vertex " << id);
      return false;
    }
  }
  if (a.switches != b.switches) { UNSCOPED_INFO("switches"); return false; }
  if (a.constraints.size() != b.constraints.size()) { UNSCOPED_INFO("edge count"); return false; }
  for (std::size_t k = 0; k < a.constraints.size(); ++k) {
    const auto& x = a.constraints[k];
    const auto& y = b.constraints[k];
    const bool same = x.id == y.id && x.from == y.from && x.to == y.to && x.kind == y.kind &&
                      x.provenance == y.provenance && x.switch_id == y.switch_id &&
                      x.maxmix_weight == y.maxmix_weight && x.decision == y.decision &&
                      PosesEqual(x.measurement.mean, y.measurement.mean, pose_tol) &&
                      x.measurement.information.isApprox(y.measurement.information, std::max(tol, 1e-300)) &&
                      (tol > 0.0 || x.measurement.information == y.measurement.information);
    if (!same) { UNSCOPED_INFO("edge " << k); return false; }
  }
  return true;
}

inline bool GraphsEqual(const AnyPoseGraph& a, const AnyPoseGraph& b, double tol = 0.0) {
  if (a.index() != b.index()) return false;
  if (const auto* a2 = std::get_if<PoseGraph2>(&a)) return GraphsEqual(*a2, std::get<PoseGraph2>(b), tol);
  return GraphsEqual(std::get<PoseGraph3>(a), std::get<PoseGraph3>(b), tol);
}

}  // namespace catgraph::testing

#endif  // CATGRAPH_TESTS_IO_GRAPH_EQUALITY_H_
