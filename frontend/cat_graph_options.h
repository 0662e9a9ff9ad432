// The options of CAT-Graph and CAT-Graph+ (CatGraphFilter): the paper's
// Table I and the spec's parameters at the top level, catgraph's additions
// nested by what they are about, each marked [D] (a departure from the spec,
// with the reason in docs/frontend.md and docs/catgraph-plus.md).
// CatGraphOptions::Paper() is the spec exactly; the defaults are catgraph's.
#ifndef CATGRAPH_FRONTEND_CAT_GRAPH_OPTIONS_H_
#define CATGRAPH_FRONTEND_CAT_GRAPH_OPTIONS_H_

#include <cstdint>
#include <optional>

#include <Eigen/Core>

namespace catgraph {

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
  // meanwhile. A vetoed closure (ClosureOverride::vetoed) releases the hold.
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

}  // namespace catgraph

#endif  // CATGRAPH_FRONTEND_CAT_GRAPH_OPTIONS_H_
