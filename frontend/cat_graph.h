// CAT-Graph: appearance-based localisation as a particle filter over the
// continuous trajectory graph (docs/catgraph-spec.md §2). Each frame:
//
//   motion    every particle moves by the frame's odometry plus noise
//             w ~ N(0, Q) in control space, in the local graph of its edge,
//             and is projected back onto the nearest edge (§2.1–2.2);
//   weights   × exp(-½ (x - y)ᵀ Q⁻¹ (x - y)) (Eq 1) × the observation likelihood
//             interpolated between the edge's two nodes (Eq 2), against a
//             new-place hypothesis of prior mass p_new (Eq 6);
//   location  the best hypothesis is the particle whose d_h-neighbourhood
//             (in its local graph) holds the most weight (Eq 4); above T_h it
//             is a loop closure: an edge from the new node to the nearer end
//             of the matched edge, with the relative pose the local graph
//             gives (§2.8–2.9);
//   resample  when ESS / n_p < T_ess, systematically, new-place draws
//             reseeding particles uniformly on eligible edges (§2.10).
//
// Nodes younger than the exclusion window are not eligible for particles,
// so the robot's own recent frames never match (§2.0); nor are nodes that
// dead reckoning rules out (the odometric gate). The additions to the spec —
// the gate, the forward-camera rule, the new-place offset and memory, the
// restart after a gap — are options (cat_graph_options.h), explained in
// docs/frontend.md.
//
// CAT-Graph+ (§3, on by default; odometric_inference.h): an odometric
// particle filter beside the visual one infers closures between visual
// closures, validated locally (d_loc) and at the next visual closure
// (d_tot); CatGraphStep::inference. Both filters move their particles and
// find their hypotheses with one ParticleKernel (particles.h) on the graph.
//
// Deterministic for a seed. Thread-compatible.
#ifndef CATGRAPH_FRONTEND_CAT_GRAPH_H_
#define CATGRAPH_FRONTEND_CAT_GRAPH_H_

#include <cstdint>
#include <functional>
#include <memory>
#include <random>
#include <vector>

#include <Eigen/Core>

#include "backend/graph/pose2.h"
#include "frontend/cat_graph_options.h"
#include "frontend/observation_model.h"
#include "frontend/odometric_inference.h"
#include "frontend/particles.h"
#include "frontend/trajectory_graph.h"

namespace catgraph {

// log p(u | u_avg) of Eq 6 up to a constant: -1/2 sum(((u - mean) / sigma)^2).
double NewPlaceMotionLogLikelihood(const Eigen::Vector3d& u, const Eigen::Vector3d& mean,
                                   const Eigen::Vector3d& sigma);

// What the caller decides about a proposed frame's visual closure
// (CatGraphFilter::Commit). The default makes the closure the filter
// proposes, if any: the filter as the spec has it.
struct ClosureOverride {
  // >= 0: the frame is taken for this old node, as when two places look
  // alike (perceptual aliasing): every visual particle is put at the node,
  // facing the way the node faced, and a visual closure to it is made
  // whatever the filter proposed. The node must be older than the exclusion
  // windows. For false-positive experiments (docs/mapping.md).
  int force_node = -1;
  // The proposed closure, if any, is not made.
  bool withhold = false;
  // A visual closure made at this frame is kept out of CAT-Graph+: it
  // neither validates the waiting inferences nor re-initialises the
  // odometric filter, which carries on from the last closure before it; nor
  // does it hold the robot on the map (NewPlaceOptions::hold_after_closure).
  // For closures the back end rejected (the front end re-run with the back
  // end's verdict, docs/mapping.md).
  bool vetoed = false;
};

struct CatGraphStep {
  int node = -1;                   // the node added for this frame
  LocationHypothesis best;
  double new_place_probability = 1.0;
  // How much better the particles explain this frame than the observation
  // model's unremarkable new place, in nats: log sum_i w_i p(z | particle
  // i) - log p(z | new place), before priors and the new-place offset;
  // NaN while no particle is on the map.
  double log_evidence = 0.0;
  // The frame's self-evidence (FrameScore::SelfEvidence), in nats.
  double self_evidence = 0.0;
  // Proposed (Propose): the filter's location is confident enough for a
  // visual closure. Committed (Commit, Step): a visual closure was made.
  bool closure = false;
  int matched_node = -1;           // the nearer end of the matched edge
  Pose2 T_node_matched;            // matched node in the frame of the new node
  int loop_edge = -1;              // the visual-loop edge added to the graph
  bool resampled = false;
  InferenceStep inference;         // CAT-Graph+ (committed steps)
};

class CatGraphFilter {
 public:
  // `model` must outlive the filter. Throws std::invalid_argument for
  // options out of range (Validate).
  CatGraphFilter(const ObservationModel& model, CatGraphOptions options);
  CatGraphFilter(const CatGraphFilter&) = delete;  // its parts refer to each other
  CatGraphFilter& operator=(const CatGraphFilter&) = delete;

  // One frame: `u` is the odometry since the previous frame (ignored for the
  // first), `z` the frame's observation. Propose, then Commit as proposed.
  CatGraphStep Step(int frame, double time_s, const Pose2& u, const Observation& z);
  // A frame observed by its words alone (FAB-MAP).
  CatGraphStep Step(int frame, double time_s, const Pose2& u, const WordSet& words) {
    return Step(frame, time_s, u, Observation{words, {}});
  }

  // A frame in two phases, for a caller that overrules the filter's closure
  // decision. Propose moves and weighs the particles, adds the frame's node
  // and says whether the filter would close (CatGraphStep::closure); Commit
  // makes the closure, or not, as `decision` says, resamples and runs
  // CAT-Graph+. Each Propose must be followed by one Commit of its step
  // before the next frame (std::logic_error otherwise). Commit throws
  // std::invalid_argument, changing nothing, for a forced node that is not
  // older than the exclusion windows.
  CatGraphStep Propose(int frame, double time_s, const Pose2& u, const Observation& z);
  void Commit(CatGraphStep& step, const ClosureOverride& decision = {});

  const TrajectoryGraph& graph() const { return graph_; }
  const std::vector<Particle>& particles() const { return particles_; }
  // CAT-Graph+'s odometric particle set O (empty until a visual closure).
  const std::vector<Particle>& odometric_particles() const { return inference_.particles(); }
  const CatGraphOptions& options() const { return options_; }

 private:
  // Nodes older than both exclusion windows have ids below this.
  int EligibleBelow() const;
  // Eligible for particles and local graphs this step: older than the
  // exclusion windows and inside the odometric gate.
  bool Eligible(int node) const;
  void SeedUniformly(std::size_t count, std::vector<Particle>& out);
  // The eligible nodes' observations ScoreFrame is given, evenly spread
  // (up to the model's PlacesWanted()).
  const std::vector<const Observation*>& PlacesForScoring();
  // Eq 2 for every particle and Eq 6 for new place, normalised jointly;
  // fills the step's new-place probability and evidence.
  void Weigh(const FrameScore& likelihood, const Pose2& u, bool restart, CatGraphStep& step);
  // Every visual particle at the start of `node`'s odometry edge (aliasing).
  LocationHypothesis PutParticlesAt(int node, int newest);
  // Eq 5 and systematic resampling with new-place reseeding (§2.10).
  bool Resample();

  const ObservationModel& model_;
  CatGraphOptions options_;
  TrajectoryGraph graph_;
  std::vector<Particle> particles_;
  std::mt19937_64 rng_;
  double time_s_ = 0.0, path_length_m_ = 0.0;
  int u_count_ = 0;
  Eigen::Vector3d u_mean_ = Eigen::Vector3d::Zero();
  int eligible_below_ = 0;                 // this step's EligibleBelow()
  Pose2 odometry_pose_;                    // dead reckoning of the current frame
  std::vector<int> seed_edges_;            // scratch: edges to reseed on ...
  std::vector<double> seed_cumulative_;    // ... and their cumulative length
  std::vector<int> eligible_scratch_;      // scratch: eligible nodes ...
  std::vector<const Observation*> places_; // ... and the observations sampled from them
  std::vector<double> node_ll_;            // this step's log p(z | L_m) ...
  std::vector<std::int64_t> node_ll_step_; // ... valid where equal to steps_
  std::vector<double> window_ll_;            // the same over observation_window_m ...
  std::vector<std::int64_t> window_ll_step_; // ... valid where equal to steps_
  std::int64_t steps_ = 0;
  double mapped_mass_ = 0.0;
  bool closed_since_entry_ = false;        // a visual closure since the mass came onto the map
  // Between Propose and Commit: the step proposed, its odometry and whether
  // it restarted the filters.
  bool proposed_ = false, proposed_restart_ = false;
  int proposed_node_ = -1;
  Pose2 proposed_u_;

  ParticleKernel kernel_;                  // over graph_, through Eligible()
  OdometricInference inference_;           // CAT-Graph+ on graph_ and kernel_
};

}  // namespace catgraph

#endif  // CATGRAPH_FRONTEND_CAT_GRAPH_H_
