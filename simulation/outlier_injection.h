// False loop closures for robust-back-end experiments: Vertigo's generator as
// re-described in ../shared/docs/robust-backend-notes.md §2, for 2D and 3D
// graphs, plus a hierarchical policy that imitates a false visual match
// followed by the closures CAT-Graph+ would infer from it.
//
// Poses are numbered 0 ... N-1 in the graph's id order. Each group of g edges
// draws one pair (v1, v2):
//   v1 uniform on {0 ... N-1-g}; v2 uniform on the same range (random) or on
//   {v1 ... min(N-1-g, v1 + local_window)} (local); the pair redrawn while
//   v1 = v2; the pair sorted; v2 = v1 + 2 when v2 = v1 + 1.
// and one measurement: dx, dy ~ N(0, 0.3 m), dtheta ~ N(0, 10 deg); in 3D
// also dz ~ N(0, 0.3 m) and roll, pitch, yaw each ~ N(0, 10 deg), the
// rotation R = Rz(yaw) Ry(pitch) Rx(roll). The group's edges are
// (v1 + j, v2 + j), j = 0 ... g-1, all with that measurement.
//
// `hierarchical`: the group's first edge (v1, v2) is a false *visual* closure
// with that measurement z; the next g-1 edges are odometry-inferred children
// (v1 + j, v2 + j) with measurement odo(v1 -> v1+j)^-1 * z * odo(v2 -> v2+j),
// the measured odometry of both traversals composed with the false match, as
// CAT-Graph+ would infer them; each child names the false visual closure as
// its parent (Provenance).
//
// `count` is the number of false edges; the last group is shorter when g does
// not divide it. The same graph, options and seed give the same edges.
#ifndef CATGRAPH_SIMULATION_OUTLIER_INJECTION_H_
#define CATGRAPH_SIMULATION_OUTLIER_INJECTION_H_

#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "backend/graph/closure_label.h"
#include "backend/graph/pose_graph.h"

namespace catgraph {

enum class OutlierPolicy {
  kRandom,         // groups of 1, pairs anywhere
  kLocal,          // groups of 1, pairs at most local_window apart
  kRandomGrouped,  // groups of g, pairs anywhere
  kLocalGrouped,   // groups of g, pairs at most local_window apart
  kHierarchical,   // a false visual closure and g-1 inferred children
};

std::string_view ToString(OutlierPolicy policy);
std::optional<OutlierPolicy> OutlierPolicyFromString(std::string_view text);

// The most false edges one injection adds, and the largest group: 100 times
// the published protocols' 1,000 (Vertigo, Latif), well within memory.
inline constexpr int kMaxOutliers = 100'000;
inline constexpr int kMaxOutlierGroupSize = 1'000;

struct OutlierOptions {
  OutlierPolicy policy = OutlierPolicy::kRandom;
  int count = 0;            // false edges to add; >= 0
  // Edges per group g; 0 = the policy's default (1 for random and local, 5
  // otherwise). Random and local take only 1.
  int group_size = 0;
  int local_window = 20;    // largest id gap of a local pair; >= 2
  std::uint64_t seed = 1;
  // The information of every false edge (3x3 for 2D, 6x6 for 3D, symmetric
  // positive definite); unset = copied from the first loop closure of the
  // graph (an error if it has none).
  std::optional<Eigen::MatrixXd> information;
};

// The group size the options resolve to. Throws std::invalid_argument naming
// the offending field.
int GroupSize(const OutlierOptions& options);
void Validate(const OutlierOptions& options);

// One false edge.
struct InjectedClosure {
  ClosureId id;
  PoseId from, to;
  int group = 0;                    // 0-based group index
  std::optional<ClosureId> parent;  // hierarchical children: their false visual closure
};

// Appends the false edges to `graph` (kind kInjected; kVisual and
// kOdometryInferred for hierarchical) with fresh closure ids and returns them
// in order. Throws std::invalid_argument for bad options, too few poses
// (N < g + 3), or a hierarchical graph without the odometry it needs.
template <typename PoseT>
std::vector<InjectedClosure> InjectOutliers(PoseGraph<PoseT>& graph, const OutlierOptions& options);
std::vector<InjectedClosure> InjectOutliers(AnyPoseGraph& graph, const OutlierOptions& options);

// One label per loop closure of `graph` (every constraint not between
// consecutive poses), in graph order: outlier exactly when it is in `injected`.
std::vector<ClosureLabel> LabelClosures(const AnyPoseGraph& graph,
                                        const std::vector<InjectedClosure>& injected);

}  // namespace catgraph

#endif  // CATGRAPH_SIMULATION_OUTLIER_INJECTION_H_
