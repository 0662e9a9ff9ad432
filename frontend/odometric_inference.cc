#include "frontend/odometric_inference.h"

#include <cmath>
#include <limits>
#include <optional>
#include <tuple>
#include <utility>

namespace catgraph {

OdometricInference::OdometricInference(const TrajectoryGraph& graph, ParticleKernel& kernel,
                                       const CatGraphOptions& options)
    : graph_(graph), kernel_(kernel), options_(options), rng_(options.seed ^ 0x9E3779B97F4A7C15ULL) {
  catgraph::Validate(options_);
}

void OdometricInference::Restart(InferenceStep& step) {
  particles_.clear();
  if (!pending_.empty()) {
    step.reference_node = reference_node_;
    step.lost = std::move(pending_);
    step.lost_reason = DiscardReason::kSequenceBreak;
  }
  pending_.clear();
  reference_node_ = -1;
}

void OdometricInference::Step(int node, const Pose2& u, bool closure, const LocationHypothesis& match,
                              const std::vector<Particle>& visual, int settled_below, InferenceStep& step) {
  if (closure) {
    if (reference_node_ >= 0 && !pending_.empty()) ValidateTotalPath(u, match, step);
    if (pending_.empty()) {
      total_path_failures_ = 0;
      Reinitialise(match, visual);
      reference_node_ = node;
      reference_location_ = match;
      T_since_reference_ = Pose2();
      return;
    }
  }
  if (reference_node_ < 0) return;  // no visual closure yet: nothing to infer from
  if (!Propagate(u)) {  // every particle left the graph: nothing to infer until the next closure
    particles_.clear();
    if (!pending_.empty()) {
      step.reference_node = reference_node_;
      step.lost = std::move(pending_);
      step.lost_reason = DiscardReason::kFilterLost;
    }
    reference_node_ = -1;
    pending_.clear();
    return;
  }
  T_since_reference_ = T_since_reference_ * u;
  step.odometric_best = kernel_.BestHypothesis(particles_);
  if (step.odometric_best.edge >= 0) ValidateLocally(node, settled_below, step);
}

void OdometricInference::ValidateTotalPath(const Pose2& u, const LocationHypothesis& match, InferenceStep& step) {
  // O's hypothesis against the visual match, in a local graph around the
  // match. O last moved with the previous frame; its hypothesis is carried
  // on by this frame's odometry, so that both are of this frame (y_p'),
  // without drawing O's noise.
  const InferenceOptions& o = options_.inference;
  const LocationHypothesis odometric = kernel_.BestHypothesis(particles_);
  double distance = std::numeric_limits<double>::infinity();
  if (odometric.edge >= 0) {
    const GraphEdge& e = graph_.edge(match.edge);
    const LocalGraph& local = kernel_.Local(e.from, o.total_validation_m + e.length_m + 1e-6);
    const auto a = local.PointPose(match.edge, match.alpha);
    const auto b = HypothesisPose(local, odometric);
    if (a && b) distance = (a->translation() - (*b * u).translation()).norm();
  }
  if (distance < o.total_validation_m || total_path_failures_ == o.total_path_retries) {
    step.reference_node = reference_node_;
    (distance < o.total_validation_m ? step.inferred : step.discarded) = std::move(pending_);
    pending_.clear();
  } else {
    ++total_path_failures_;  // carried past this closure, as past a vetoed one
  }
}

void OdometricInference::Reinitialise(const LocationHypothesis& match, const std::vector<Particle>& visual) {
  // §3.5 copies V; here only V's particles within d_h of the match, each
  // copied `particle_factor` times (InferenceOptions). The match is the
  // weighted mean of the particles in Eq 4's winning disc, so it has
  // particles near; should none lie within d_h, O is the spec's copy of V.
  seeds_.clear();
  if (options_.inference.seed_local) {
    const GraphEdge& e = graph_.edge(match.edge);
    const double r = options_.hypothesis_radius_m;
    const LocalGraph& local = kernel_.Local(e.from, r + e.length_m + 1e-6);
    if (const std::optional<Pose2> centre = local.PointPose(match.edge, match.alpha)) {
      for (const Particle& p : visual) {
        if (p.log_weight == kNegInf) continue;
        const std::optional<Pose2> x = local.PointPose(p.edge, p.alpha);
        if (x && (x->translation() - centre->translation()).norm() <= r) seeds_.push_back(p);
      }
    }
  }
  if (seeds_.empty()) seeds_ = visual;  // the spec's copy of V
  const int factor = options_.inference.particle_factor;
  // Each copy weighs w / (factor × the seeds' total).
  const double log_total = LogTotalWeight(seeds_) + std::log(static_cast<double>(factor));
  particles_.clear();
  particles_.reserve(seeds_.size() * static_cast<std::size_t>(factor));
  for (const Particle& p : seeds_) {
    for (int k = 0; k < factor; ++k) {
      particles_.push_back(p);
      particles_.back().log_weight -= log_total;
    }
  }
}

bool OdometricInference::Propagate(const Pose2& u) {
  // The visual filter's motion and projection; Q O's own if set.
  kernel_.Move(particles_, u, options_.inference.motion_sigma.value_or(options_.motion_sigma), rng_);
  const double log_total = LogTotalWeight(particles_);
  if (log_total == kNegInf) return false;
  double sum_sq = 0.0;
  for (Particle& p : particles_) {
    p.log_weight -= log_total;
    sum_sq += std::exp(2.0 * p.log_weight);
  }
  if (1.0 / sum_sq < options_.ess_threshold * static_cast<double>(particles_.size())) {
    std::size_t beyond = 0;
    particles_ = SystematicResample(particles_, static_cast<int>(particles_.size()), rng_, &beyond);
    for (Particle& p : particles_) p.log_weight = -std::log(static_cast<double>(particles_.size()));
  }
  return true;
}

void OdometricInference::ValidateLocally(int node, int settled_below, InferenceStep& step) {
  // O's hypothesis relative to the last visual match, along the old graph's
  // shortest path, against the odometry since then. Through nodes older
  // than the exclusion windows only, not through the odometric gate: the
  // gate is about where the robot may be now, and the reference lies behind
  // it.
  const GraphEdge& e = graph_.edge(reference_location_.edge);
  const double radius = T_since_reference_.translation().norm() + options_.inference.local_validation_m + e.length_m;
  const LocalGraph& local = kernel_.Local(e.from, radius, [settled_below](int n) { return n < settled_below; });
  const auto from = HypothesisPose(local, reference_location_);
  const auto to = HypothesisPose(local, step.odometric_best);
  if (!from || !to) return;
  const Pose2 y = from->Between(*to);
  if ((y.translation() - T_since_reference_.translation()).norm() >= options_.inference.local_validation_m) return;
  step.pending = true;
  InferredClosure c;
  c.node = node;
  c.location = step.odometric_best;
  std::tie(c.matched_node, c.T_node_matched) = kernel_.LoopTo(step.odometric_best);
  pending_.push_back(c);
}

}  // namespace catgraph
