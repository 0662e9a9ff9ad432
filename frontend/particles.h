// Particles on the continuous trajectory graph and what both of CAT-Graph's
// filters do with them (docs/catgraph-spec.md §2): log-weight arithmetic,
// systematic resampling (§2.10), the position likelihood (Eq 1), and, on a
// graph, motion with projection (§2.1–2.2) and the location hypothesis
// (Eq 4).
//
// ParticleKernel is thread-compatible: it keeps scratch space (one local
// graph at a time) between calls.
#ifndef CATGRAPH_FRONTEND_PARTICLES_H_
#define CATGRAPH_FRONTEND_PARTICLES_H_

#include <cstddef>
#include <functional>
#include <limits>
#include <optional>
#include <random>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "backend/graph/pose2.h"
#include "frontend/trajectory_graph.h"

namespace catgraph {

inline constexpr double kNegInf = -std::numeric_limits<double>::infinity();

struct Particle {
  int edge = -1;
  double alpha = 0.0;   // fraction along the edge from its start
  int direction = 1;    // +1 along the edge, -1 against it
  double log_weight = 0.0;
};

// A point on the graph: the particle-weighted location of Eq 4.
struct LocationHypothesis {
  int edge = -1;         // -1: none (no particles)
  double alpha = 0.0;
  int direction = 1;
  double value = 0.0;    // Eq 4: weight within d_h
};

// log(exp(a) + exp(b)), exact where either is -infinity.
double LogSumExp(double a, double b);

// log of the particles' total weight (-infinity for none).
double LogTotalWeight(const std::vector<Particle>& particles);

// Eq 5: (sum w)² / sum w², the effective number of particles (0 for none or
// no weight).
double EffectiveSampleSize(const std::vector<Particle>& particles);

// Systematic resampling: n draws at spacing 1/n from one uniform offset over
// the particles' weights, which may sum to less than 1; draws past the last
// particle (the rest of the unit mass) are counted in *beyond. The drawn
// particles keep their weights.
std::vector<Particle> SystematicResample(const std::vector<Particle>& particles, int n, std::mt19937_64& rng,
                                         std::size_t* beyond);

// log P(x_k | y_k, Q) of Eq 1 up to a constant: the projected pose x (path
// heading, turned by π for a particle facing against the path) against the
// propagated pose y, in the frame of the particle's pose at the start of
// the step (spec §2.1: Q is in control space), so that sigma's first two
// entries weigh the offset along and across the robot's way whatever the
// path's direction. Heading only when `with_heading`.
double PositionLogLikelihood(const Pose2& start, const Pose2& y, const Pose2& x, const Eigen::Vector3d& sigma,
                             bool with_heading);

// The pose of a hypothesis in a local graph (heading turned by π for
// direction −1); none when its edge is not in the local graph.
std::optional<Pose2> HypothesisPose(const LocalGraph& local, const LocationHypothesis& h);

// The operations on particles that need the graph: motion with projection,
// Eq 4, and local graphs around a point. Both filters share one kernel (and
// its scratch) over the graph they grow.
class ParticleKernel {
 public:
  struct Options {
    double motion_radius_m = 0.5;          // local-graph radius for motion, at least
    bool heading_in_position_likelihood = true;
    double hypothesis_radius_m = 1.0;      // d_h
    int hypothesis_candidate_edges = 64;   // Eq 4 is evaluated on the heaviest edges
  };

  // `graph` must outlive the kernel; `eligible` says which nodes particles
  // may reach (a node that is not is not in their local graphs).
  ParticleKernel(const TrajectoryGraph& graph, Options options, std::function<bool(int)> eligible);
  ParticleKernel(const ParticleKernel&) = delete;
  ParticleKernel& operator=(const ParticleKernel&) = delete;

  // Moves each particle by u plus noise of σ `sigma` drawn from `rng`, in the
  // local graph of its edge, projects it back onto the nearest edge and adds
  // log Eq 1 (with the same σ) to its weight. A particle whose edge or
  // projection leaves the eligible graph gets weight 0 (-infinity).
  void Move(std::vector<Particle>& particles, const Pose2& u, const Eigen::Vector3d& sigma, std::mt19937_64& rng);

  // Eq 4: the candidate whose d_h-disc in its local graph holds the most
  // weight, reported at the weighted mean of the particles in that disc
  // projected back onto the graph, facing the way most of their weight
  // faces. Candidates are the heaviest particle of every 0.1 m of the
  // `hypothesis_candidate_edges` heaviest edges. No edge for no weight.
  LocationHypothesis BestHypothesis(const std::vector<Particle>& particles);

  // The local graph around node `centre` within `radius_m`, through the
  // eligible nodes, or those `eligible` admits; valid until the next call of
  // any method.
  const LocalGraph& Local(int centre, double radius_m) { return Local(centre, radius_m, eligible_); }
  const LocalGraph& Local(int centre, double radius_m, const std::function<bool(int)>& eligible);

  // The loop edge a hypothesis gives: the nearer end of its edge and that
  // node's pose in the hypothesis' frame.
  std::pair<int, Pose2> LoopTo(const LocationHypothesis& h);

 private:
  const TrajectoryGraph& graph_;
  Options options_;
  std::function<bool(int)> eligible_;
  LocalGraphBuilder builder_;
  LocalGraph local_;
  std::vector<std::size_t> order_;  // particle indices by edge
  std::vector<double> weight_;      // their weights, in order_
};

}  // namespace catgraph

#endif  // CATGRAPH_FRONTEND_PARTICLES_H_
