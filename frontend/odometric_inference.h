// CAT-Graph+ (docs/catgraph-spec.md §3; docs/catgraph-plus.md): an
// odometry-only particle filter O beside the visual one, started from the
// visual particles at each visual closure, that infers where the robot is
// on the old trajectory while the camera recognises nothing. Each of its
// hypotheses that agrees with the odometry since the last visual closure
// (local validation, d_loc) waits; the next visual closure validates the
// waiting ones if O agrees with it (total-path validation, d_tot) and
// discards them if not.
//
// OdometricInference runs on the visual filter's graph and particle kernel
// (CatGraphFilter owns all three). Deterministic for a seed; O's noise is
// its own, so the visual filter never depends on it. Thread-compatible.
#ifndef CATGRAPH_FRONTEND_ODOMETRIC_INFERENCE_H_
#define CATGRAPH_FRONTEND_ODOMETRIC_INFERENCE_H_

#include <cstdint>
#include <random>
#include <vector>

#include "backend/graph/pose2.h"
#include "frontend/cat_graph_options.h"
#include "frontend/particles.h"
#include "frontend/trajectory_graph.h"

namespace catgraph {

// Why CAT-Graph+ did not emit a pending inference.
enum class DiscardReason {
  kTotalPath,      // the next visual closure failed total-path validation (d_tot)
  kFilterLost,     // every odometric particle left the graph (or the odometric gate)
  kSequenceBreak,  // a gap in the frames restarted the filters (sequence_break_s)
};

// An odometry-inferred closure (CAT-Graph+): frame node `node` is at
// `location` on the old trajectory.
struct InferredClosure {
  int node = -1;
  LocationHypothesis location;     // the odometric filter's best hypothesis then
  int matched_node = -1;           // the nearer end of the matched edge
  Pose2 T_node_matched;
};

// What CAT-Graph+ did in one frame.
struct InferenceStep {
  // Between visual closures: O's best hypothesis and whether this frame
  // passed local validation (d_loc) and waits for the next visual closure.
  LocationHypothesis odometric_best;
  bool pending = false;
  // At a visual closure that follows an earlier one (the node of which is
  // `reference_node`): the waiting inferences it validated (d_tot) or
  // discarded.
  int reference_node = -1;
  std::vector<InferredClosure> inferred;
  std::vector<InferredClosure> discarded;
  // Waiting inferences dropped with no visual closure to validate them, and
  // why; `reference_node` is then the closure they hung from.
  std::vector<InferredClosure> lost;
  DiscardReason lost_reason = DiscardReason::kFilterLost;
};

class OdometricInference {
 public:
  // `graph` and `kernel` must outlive this; `options` are the filter's
  // (inference, motion_sigma, ess_threshold, hypothesis_radius_m, seed).
  // Throws std::invalid_argument for options out of range.
  OdometricInference(const TrajectoryGraph& graph, ParticleKernel& kernel, const CatGraphOptions& options);

  // A gap in the frames: O and the waiting inferences are dropped (reported
  // in `step` as lost); nothing is inferred until the next visual closure.
  void Restart(InferenceStep& step);

  // One frame, after the visual filter's (its node `node` added, the visual
  // particles `visual` resampled or not). `u`: the odometry since the last
  // frame. `closure`: a visual closure CAT-Graph+ may use was made at
  // `match`. Nodes below `settled_below` are older than the exclusion
  // windows (local validation runs through them alone).
  void Step(int node, const Pose2& u, bool closure, const LocationHypothesis& match,
            const std::vector<Particle>& visual, int settled_below, InferenceStep& step);

  // The odometric particle set O (empty until a visual closure).
  const std::vector<Particle>& particles() const { return particles_; }

 private:
  // Total-path validation (§3.4) of the waiting inferences against a visual
  // closure at `match`, O carried on by `u`.
  void ValidateTotalPath(const Pose2& u, const LocationHypothesis& match, InferenceStep& step);
  // O from V at a visual closure matched at `match` (§3.5; InferenceOptions).
  void Reinitialise(const LocationHypothesis& match, const std::vector<Particle>& visual);
  // Motion, Eq 8's position-only weights and resampling without new places;
  // false when every particle left the graph.
  bool Propagate(const Pose2& u);
  // Local validation (§3.3, Eq 9–11) of O's best hypothesis for node `node`.
  void ValidateLocally(int node, int settled_below, InferenceStep& step);

  const TrajectoryGraph& graph_;
  ParticleKernel& kernel_;
  const CatGraphOptions options_;
  std::vector<Particle> particles_;        // O
  std::mt19937_64 rng_;
  std::vector<Particle> seeds_;            // scratch: V's particles O starts from
  int reference_node_ = -1;                // N_j of the last visual closure
  LocationHypothesis reference_location_;  // y_j'
  Pose2 T_since_reference_;                // odometry since j
  std::vector<InferredClosure> pending_;
  int total_path_failures_ = 0;            // closures in a row the waiting chain was carried past
};

}  // namespace catgraph

#endif  // CATGRAPH_FRONTEND_ODOMETRIC_INFERENCE_H_
