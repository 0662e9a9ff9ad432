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
// restart after a gap — are options, explained in docs/frontend.md.
//
// CAT-Graph+ (§3, on by default): an odometric particle filter beside the
// visual one infers closures between visual closures, validated locally
// (d_loc) and at the next visual closure (d_tot); CatGraphStep::inferred.
//
// Deterministic for a seed. Thread-compatible.
#ifndef CATGRAPH_FRONTEND_CAT_GRAPH_H_
#define CATGRAPH_FRONTEND_CAT_GRAPH_H_

#include <cstdint>
#include <functional>
#include <optional>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "backend/graph/pose2.h"
#include "frontend/observation_model.h"
#include "frontend/trajectory_graph.h"

namespace catgraph {

// log P(x_k | y_k, Q) of Eq 1 up to a constant: the projected pose x (path
// heading, turned by π for a particle facing against the path) against the
// propagated pose y, in the frame of the particle's pose at the start of
// the step (spec §2.1: Q is in control space), so that sigma's first two
// entries weigh the offset along and across the robot's way whatever the
// path's direction. Heading only when `with_heading`.
double PositionLogLikelihood(const Pose2& start, const Pose2& y, const Pose2& x, const Eigen::Vector3d& sigma,
                             bool with_heading);

// log p(u | u_avg) of Eq 6 up to a constant: -1/2 sum(((u - mean) / sigma)^2).
double NewPlaceMotionLogLikelihood(const Eigen::Vector3d& u, const Eigen::Vector3d& mean,
                                   const Eigen::Vector3d& sigma);

// The most particles a filter takes: memory grows by about 100 bytes per
// particle and the time per frame linearly (docs/cli.md "Limits").
inline constexpr int kMaxParticles = 100'000;

// What counts as the camera recognising a place [D, docs/frontend.md].
struct RecognitionOptions {
  // A visual closure also needs the frame's evidence (CatGraphStep's
  // log_evidence: how much better the particles explain it than the mean
  // field) to be at least this fraction of its self-evidence (what a node
  // with exactly its words would score) ("Closing on what the camera
  // sees"): a cloud that the odometry holds together through a changed
  // place is still no recognition. [0, 1]; 0: Eq 4 and T_h alone (the spec).
  double closure_min_evidence = 0.2;
  // The camera sees one way (the paper's forward patch), so particles facing
  // against the nodes' headings get the model's unseen-place likelihood
  // (FAB-MAP's mean field), not the nodes', and a hypothesis facing against
  // them is no visual closure: the camera cannot have recognised what it
  // did not see. False for a panoramic camera (spec Eq 2 as written).
  bool forward_camera = true;
  // Eq 2 over a stretch of path ("What stays and what changes"): a node's
  // likelihood is the mean of those of the eligible nodes within this many
  // metres of path on either side of it (none across a sequence break). A
  // camera on a line beside the map's sees a corner's walls as the map saw
  // them a little earlier or later, and the images pull the particles that
  // far along the path; within the window they do not, and the odometry
  // holds the cloud. >= 0; 0: the node's own (the spec).
  double observation_window_m = 0.4;
};

// The new-place hypothesis of Eq 6 and what entering, staying on and leaving
// the map cost [D, docs/frontend.md].
struct NewPlaceOptions {
  // Added to log p(z | new place), in the observation model's nats. Unset:
  // the model's own (ObservationModel::NewPlaceLogOffset: FAB-MAP's 45, none
  // for the calibrated holistic model); 0 is the spec as written. Finite
  // when set.
  std::optional<double> log_offset;
  // Prior mass of new place while the robot was localised on the map (the
  // chance of leaving it in one frame), in place of p_new; (0, 1). Small, so
  // that one weak frame does not take the robot off the map: ln((1 - h) / h)
  // = 46 nats for 1e-20, against which the frames score what the stay
  // offset below leaves them ("Leaving the map", "Staying on the map").
  double leave_probability = 1e-20;
  // What staying on the map costs, as a fraction of what entering it costs
  // ("Staying on the map"): the offset is charged in full against the map's
  // mass entering from a new place, and, once the robot is on the map (at
  // least half the mass there last frame), only this fraction of it against
  // the mass carried on. [0, 1]; 1: one offset for both.
  double stay_fraction = 0.2;
  // And staying costs this fraction of the frame's self-evidence more (at
  // most what entering costs): in 99 % of the unchanged office frames the
  // true place scores a fifth of the frame's self-evidence or more, in most
  // changed ones under a tenth. [0, 1); 0: the stay fraction alone.
  double stay_relative_offset = 0.08;
  // Whether the robot is held on the map (the leave probability in place of
  // p_new, and the stay credit) only once the cloud has made a visual
  // closure since it came onto the map ("Held after a closure"). A cloud
  // that came on without beating the offset (new place charged for a turn
  // by Eq 6, say) then still has to beat new place frame by frame until it
  // closes, and the new place's reseeding can find the true place
  // meanwhile. A vetoed closure (Aliasing::vetoed) releases the hold.
  // False: any mass on the map holds it.
  bool hold_after_closure = true;
  // Eq 6's σ: how much a new place is charged for odometry unlike the mean
  // ("Corners and Q"). The default is the odometry's own noise (Q's σ
  // before its heading σ was widened for corners): a turn the map does not
  // make still costs new place what it did. Unset: Q's σ (motion_sigma),
  // the spec's reading (§6.3). Finite and > 0 when set.
  std::optional<Eigen::Vector3d> motion_sigma = Eigen::Vector3d(0.05, 0.05, 0.005);
};

// The odometric gate [D, docs/frontend.md "The odometric gate"]: a node is
// not eligible while dead reckoning puts it farther from the robot than
// base + fraction × the path driven since it, i.e. while odometry alone
// rules out being there.
struct OdometricGateOptions {
  bool enabled = true;
  double base_m = 1.0;    // >= 0
  double fraction = 0.1;  // of the path since the node; >= 0
};

// CAT-Graph+ (spec §3; the paper's Table II): an odometry-only particle
// filter beside the visual one infers closures between visual closures
// (docs/catgraph-plus.md).
struct InferenceOptions {
  bool enabled = true;
  double local_validation_m = 2.0;  // d_loc; > 0
  double total_validation_m = 1.0;  // d_tot; > 0
  // How many visual closures in a row the pending inferences may fail
  // total-path validation against and still be carried on, O with them, to
  // the next one [D, "A chain against a false closure"]. A failure says that
  // the chain or the closure is wrong, not which; a false visual closure
  // (perceptual aliasing) otherwise discards the true chain it meets, and
  // the closures it brings then start a false one. A closure a chain is
  // carried past neither validates, discards nor re-initialises O (as a
  // vetoed one). [0, 100]; 0: the spec.
  int total_path_retries = 4;
  // How O is re-initialised at a visual closure (spec §3.5 copies V) [D,
  // "O's along-track wander"]. O has no observation: its cloud's centre
  // walks along the track with each resampling, by chance, less so the more
  // particles it holds; and a particle of V far from the match (a new-place
  // draw) that moves with the odometry is as good as the main cloud, and
  // can grow into a second mode. So O takes only V's particles within d_h
  // of the match (false: all of V, the spec), each copied this many times
  // at 1/factor of its weight (1: the spec); [1, 100].
  bool seed_local = true;
  int particle_factor = 5;
  // O's Q, σ per frame (m, m, rad): O only needs Q to cover how the odometry
  // of the two traversals differs, which can be less than what the visual
  // filter needs. Unset: motion_sigma (the spec: the same propagation as
  // V). Finite and > 0 when set. V never depends on it.
  std::optional<Eigen::Vector3d> motion_sigma;
};

// The filter's options. The top level holds the paper's Table I and the
// spec's parameters; the nested structs hold what catgraph adds, each
// marked [D] (a departure from the spec, with the reason in docs/). Paper()
// is the spec exactly; the defaults are catgraph's.
struct CatGraphOptions {
  int num_particles = 1000;                // n_p; 1 to kMaxParticles
  double closure_threshold = 0.8;          // T_h on Eq 4; (0, 1]
  double hypothesis_radius_m = 1.0;        // d_h; > 0
  // Q = diag(σ)², per frame (m, m, rad); > 0. The heading's σ is wider than
  // Table I's (0.005 rad) so that the cloud follows a corner the robot takes
  // a little sooner or later than the map did [D, docs/frontend.md
  // "Corners and Q"].
  Eigen::Vector3d motion_sigma{0.05, 0.05, 0.02};
  double ess_threshold = 0.3;              // T_ess, a fraction of n_p; (0, 1]
  double new_place_prior = 0.5;            // p_new (spec §6.3) while in a new place; (0, 1)
  double exclusion_window_s = 10.0;        // nodes younger than this ...
  double exclusion_window_m = 5.0;         // ... or nearer along the path are not eligible; >= 0
  bool heading_in_position_likelihood = true;  // Eq 1 with θ (spec §6.4: false = position only)
  // A gap between frames longer than this restarts the particles (the
  // traversals of a dataset recorded apart); > 0.
  double sequence_break_s = 5.0;
  double motion_radius_m = 0.5;            // local-graph radius for the motion update, at least
                                           // the frame's step + 4σ; > 0
  int hypothesis_candidate_edges = 64;     // Eq 4 is evaluated on the heaviest edges; >= 1
  std::uint64_t seed = 1;

  RecognitionOptions recognition;
  NewPlaceOptions new_place;
  OdometricGateOptions gate;
  InferenceOptions inference;

  // The spec exactly: Table I (Q's heading σ 0.005 rad), Eq 2 and Eq 6 as
  // written, no gate, CAT-Graph+ as §3 has it.
  static CatGraphOptions Paper();
};

// Throws std::invalid_argument naming the first field out of range.
void Validate(const CatGraphOptions& options);

// Whether every entry of a σ (motion_sigma, new_place_motion_sigma, ...) is
// finite and > 0.
bool IsValidSigma(const Eigen::Vector3d& sigma);

// The odometric gate's radius for a node `path_since_m` of path behind the
// robot: a node farther than this from the robot by dead reckoning is not
// eligible (infinite when the gate is off).
double OdometricGateRadius(const CatGraphOptions& options, double path_since_m);

struct Particle {
  int edge = -1;
  double alpha = 0.0;   // fraction along the edge from its start
  int direction = 1;    // +1 along the edge, -1 against it
  double log_weight = 0.0;
};

struct LocationHypothesis {
  int edge = -1;         // -1: none (no particles)
  double alpha = 0.0;
  int direction = 1;
  double value = 0.0;    // Eq 4: weight within d_h
};

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

// Perceptual aliasing imposed on one step, for false-positive experiments
// (`catgraph map --inject-false-visual`, docs/mapping.md). The default is
// none: the filter as the spec has it.
struct Aliasing {
  // >= 0: the frame is taken for this old node, as when two places look
  // alike: every visual particle is put at the node, facing the way the
  // node faced, and a visual closure to it is reported whatever the
  // filter believed. The node must be older than the exclusion windows.
  int false_match = -1;
  // The filter's own closure, if it makes one, is withheld (the frames
  // between a pair of false matches, while the aliasing lasts).
  bool withhold_closure = false;
  // A visual closure at this frame is still reported but kept out of
  // CAT-Graph+: it neither validates the pending inferences nor
  // re-initialises the odometric filter, which carries on from the last
  // closure before it. For closures the back end rejected (a re-run of the
  // front end with the back end's verdict, docs/mapping.md). Nor does it
  // count as a closure that holds the robot on the map
  // (CatGraphOptions::hold_after_closure).
  bool vetoed = false;
};

struct CatGraphStep {
  int node = -1;                   // the node added for this frame
  LocationHypothesis best;
  double new_place_probability = 1.0;
  // How much better the particles explain this frame than FAB-MAP's mean
  // field (an unremarkable new place), in nats: log sum_i w_i p(z | particle
  // i) - log p(z | mean field), before priors and the new-place offset;
  // NaN while no particle is on the map.
  double log_evidence = 0.0;
  // The frame's self-evidence (FrameScore::SelfEvidence), in nats.
  double self_evidence = 0.0;
  bool closure = false;
  int matched_node = -1;           // the nearer end of the matched edge
  Pose2 T_node_matched;            // matched node in the frame of the new node
  int loop_edge = -1;              // the visual-loop edge added to the graph
  bool resampled = false;

  // CAT-Graph+. Between visual closures: the odometric filter's best
  // hypothesis and whether this frame passed local validation (d_loc) and
  // waits for the next visual closure.
  LocationHypothesis odometric_best;
  bool inference_pending = false;
  // At a visual closure that follows an earlier one (the node of which is
  // `reference_node`): the pending inferences it validated (d_tot) or
  // discarded.
  int reference_node = -1;
  std::vector<InferredClosure> inferred;
  std::vector<InferredClosure> discarded;
  // Pending inferences dropped with no visual closure to validate them, and
  // why; `reference_node` is then the closure they hung from.
  std::vector<InferredClosure> lost;
  DiscardReason lost_reason = DiscardReason::kFilterLost;
};

class CatGraphFilter {
 public:
  // `model` must outlive the filter.
  CatGraphFilter(const ObservationModel& model, CatGraphOptions options);
  CatGraphFilter(const CatGraphFilter&) = delete;  // holds a callback on itself
  CatGraphFilter& operator=(const CatGraphFilter&) = delete;

  // One frame: `u` is the odometry since the previous frame (ignored for the
  // first), `z` the frame's observation. Throws std::invalid_argument for an
  // aliasing onto a node that is not eligible by age.
  CatGraphStep Step(int frame, double time_s, const Pose2& u, const Observation& z, const Aliasing& aliasing = {});
  // A frame observed by its words alone (FAB-MAP).
  CatGraphStep Step(int frame, double time_s, const Pose2& u, const WordSet& words, const Aliasing& aliasing = {}) {
    return Step(frame, time_s, u, Observation{words, {}}, aliasing);
  }

  const TrajectoryGraph& graph() const { return graph_; }
  const std::vector<Particle>& particles() const { return particles_; }
  // CAT-Graph+'s odometric particle set O (empty until a visual closure).
  const std::vector<Particle>& odometric_particles() const { return odometric_; }
  const CatGraphOptions& options() const { return options_; }

 private:
  // Nodes older than both exclusion windows have ids below this.
  int EligibleBelow() const;
  // Eligible for particles and local graphs this step: older than the
  // exclusion windows and inside the odometric gate.
  bool Eligible(int node) const;
  void SeedUniformly(std::size_t count, std::vector<Particle>& out);
  // Moves the particles by u plus noise of σ `sigma` and projects them back;
  // adds log Eq 1 (with the same σ).
  void MotionAndProjection(std::vector<Particle>& particles, const Pose2& u, const Eigen::Vector3d& sigma,
                           std::mt19937_64& rng);
  LocationHypothesis BestHypothesis(const std::vector<Particle>& particles);
  // The pose of a hypothesis (heading turned by π for direction −1) in the
  // local graph `local_` holds.
  std::optional<Pose2> HypothesisPose(const LocationHypothesis& h) const;
  // The loop edge a hypothesis gives: the nearer end of its edge and that
  // node's pose in the hypothesis' frame.
  std::pair<int, Pose2> LoopTo(const LocationHypothesis& h);
  // CAT-Graph+ after the visual step (spec §3).
  // `closure`: a visual closure CAT-Graph+ may use was made this step.
  void OdometricStep(const Pose2& u, bool closure, CatGraphStep& step);
  // O from V at a visual closure matched at `match` (§3.5; CatGraphOptions).
  void ReinitialiseOdometric(const LocationHypothesis& match);

  // The eligible nodes' observations ScoreFrame is given, evenly spread
  // (up to the model's PlacesWanted()).
  const std::vector<const Observation*>& PlacesForScoring();

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
  std::function<bool(int)> eligible_;      // Eligible() for the builder
  std::vector<int> seed_edges_;            // scratch: edges to reseed on ...
  std::vector<double> seed_cumulative_;    // ... and their cumulative length
  std::vector<int> eligible_scratch_;      // scratch: eligible nodes ...
  std::vector<const Observation*> places_; // ... and the observations sampled from them
  LocalGraphBuilder builder_;
  LocalGraph local_;                       // scratch
  std::vector<std::size_t> order_;         // scratch: particle indices by edge
  std::vector<double> weight_;             // scratch: their weights, in order_
  std::vector<double> node_ll_;            // this step's log p(z | L_m) ...
  std::vector<std::int64_t> node_ll_step_; // ... valid where equal to steps_
  std::vector<double> window_ll_;            // the same over observation_window_m ...
  std::vector<std::int64_t> window_ll_step_; // ... valid where equal to steps_
  std::int64_t steps_ = 0;
  double mapped_mass_ = 0.0;
  bool closed_since_entry_ = false;        // a visual closure since the mass came onto the map
  int total_path_failures_ = 0;            // closures in a row the pending chain was carried past

  // CAT-Graph+ state (spec §3.2).
  std::vector<Particle> odometric_;        // the odometric particle set O
  std::mt19937_64 odometric_rng_;          // its own noise: V never depends on O
  std::vector<Particle> odometric_seeds_;  // scratch: V's particles O starts from
  int reference_node_ = -1;                // N_j of the last visual closure
  LocationHypothesis reference_location_;  // y_j'
  Pose2 T_since_reference_;                // odometry since j
  std::vector<InferredClosure> pending_;
};

}  // namespace catgraph

#endif  // CATGRAPH_FRONTEND_CAT_GRAPH_H_
