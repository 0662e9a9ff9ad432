#include "frontend/cat_graph.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

namespace catgraph {

CatGraphFilter::CatGraphFilter(const ObservationModel& model, CatGraphOptions options)
    : model_(model),
      options_(std::move(options)),
      rng_(options_.seed),
      kernel_(graph_,
              {.motion_radius_m = options_.motion_radius_m,
               .heading_in_position_likelihood = options_.heading_in_position_likelihood,
               .hypothesis_radius_m = options_.hypothesis_radius_m,
               .hypothesis_candidate_edges = options_.hypothesis_candidate_edges},
              [this](int n) { return Eligible(n); }),
      inference_(graph_, kernel_, options_) {
  Validate(options_);
}

int CatGraphFilter::EligibleBelow() const {
  // Time and path length grow with the node id, so the eligible nodes are a
  // prefix.
  const auto& nodes = graph_.nodes();
  const auto first_ineligible = std::partition_point(nodes.begin(), nodes.end(), [this](const GraphNode& n) {
    return time_s_ - n.time_s >= options_.exclusion_window_s &&
           path_length_m_ - n.path_length_m >= options_.exclusion_window_m;
  });
  return static_cast<int>(first_ineligible - nodes.begin());
}

double NewPlaceMotionLogLikelihood(const Eigen::Vector3d& u, const Eigen::Vector3d& mean,
                                   const Eigen::Vector3d& sigma) {
  return -0.5 * (u - mean).cwiseQuotient(sigma).squaredNorm();
}

bool CatGraphFilter::Eligible(int node) const {
  if (node >= eligible_below_) return false;
  if (!options_.gate.enabled) return true;
  const GraphNode& n = graph_.node(node);
  const double gate = OdometricGateRadius(options_, path_length_m_ - n.path_length_m);
  return (odometry_pose_.translation() - n.odometry_pose.translation()).squaredNorm() <= gate * gate;
}

void CatGraphFilter::SeedUniformly(std::size_t count, std::vector<Particle>& out) {
  if (count == 0) return;
  // Eligible, non-degenerate edges, drawn in proportion to their length.
  // An edge's newer end is its largest node id, which never decreases with
  // the edge id, so the edges older than the exclusion windows are a prefix;
  // within it one pass applies the odometric gate (a few ns per edge; the
  // gate usually leaves too few edges for drawing and rejecting).
  const auto& edges = graph_.edges();
  const auto prefix = std::partition_point(edges.begin(), edges.end(), [this](const GraphEdge& e) {
    return std::max(e.from, e.to) < eligible_below_;
  });
  seed_edges_.clear();
  seed_cumulative_.clear();
  double total = 0.0;
  for (auto e = edges.begin(); e != prefix; ++e) {
    if (e->length_m < 1e-6 || !Eligible(e->from) || !Eligible(e->to)) continue;
    total += e->length_m;
    seed_edges_.push_back(static_cast<int>(e - edges.begin()));
    seed_cumulative_.push_back(total);
  }
  if (seed_edges_.empty()) return;
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (std::size_t i = 0; i < count; ++i) {
    const double r = unit(rng_) * total;
    const auto k = static_cast<std::size_t>(
        std::upper_bound(seed_cumulative_.begin(), seed_cumulative_.end(), r) - seed_cumulative_.begin());
    out.push_back({seed_edges_[std::min(k, seed_edges_.size() - 1)], unit(rng_), unit(rng_) < 0.5 ? 1 : -1, 0.0});
  }
}

const std::vector<const Observation*>& CatGraphFilter::PlacesForScoring() {
  places_.clear();
  const int wanted = model_.PlacesWanted();
  if (wanted <= 0) return places_;
  eligible_scratch_.clear();
  for (int n = 0; n < eligible_below_; ++n) {
    if (Eligible(n)) eligible_scratch_.push_back(n);
  }
  for (const std::size_t k : EvenlySpread(eligible_scratch_.size(), wanted)) {
    places_.push_back(&graph_.node(eligible_scratch_[k]).observation);
  }
  return places_;
}

CatGraphStep CatGraphFilter::Step(int frame, double time_s, const Pose2& u, const Observation& z) {
  CatGraphStep step = Propose(frame, time_s, u, z);
  Commit(step);
  return step;
}

CatGraphStep CatGraphFilter::Propose(int frame, double time_s, const Pose2& u, const Observation& z) {
  if (proposed_) throw std::logic_error("CatGraphFilter: Propose again before the last step's Commit");
  const bool first = graph_.nodes().empty();
  // After a gap in the frames (traversals recorded apart) the motion since
  // the previous frame says nothing about where the particles went: they are
  // seeded afresh and the motion terms are left out for this frame.
  const bool restart = first || time_s - time_s_ > options_.sequence_break_s;
  CatGraphStep step;
  if (restart && !first) {
    particles_.clear();
    inference_.Restart(step.inference);  // CAT-Graph+ waits for the next visual closure
    closed_since_entry_ = false;
  }
  time_s_ = time_s;
  if (!first) path_length_m_ += u.translation().norm();
  if (!first) odometry_pose_ = odometry_pose_ * u;
  eligible_below_ = EligibleBelow();
  const std::unique_ptr<FrameScore> likelihood = model_.ScoreFrame(z, PlacesForScoring());
  if (particles_.empty()) {
    SeedUniformly(static_cast<std::size_t>(options_.num_particles), particles_);
    for (Particle& p : particles_) p.log_weight = -std::log(static_cast<double>(particles_.size()));
  }
  Weigh(*likelihood, u, restart, step);

  // Location hypothesis and loop closure (Eq 4).
  step.best = kernel_.BestHypothesis(particles_);
  const int previous = first ? -1 : static_cast<int>(graph_.nodes().size()) - 1;
  step.node = graph_.AddNode(frame, time_s, path_length_m_, odometry_pose_, z);
  if (previous >= 0) graph_.AddEdge(previous, step.node, u, EdgeType::kOdometry);
  // A forward camera facing against the matched nodes saw none of what they
  // saw: its particles carry no visual evidence (Weigh), only the
  // odometry's, and their hypothesis is no visual closure.
  const bool seen = !(options_.recognition.forward_camera && step.best.direction < 0);
  // Nor is a cloud that scores little on what the camera sees (NaN, no
  // particle on the map, fails too).
  const bool recognised = options_.recognition.closure_min_evidence == 0.0 ||
                          step.log_evidence >= options_.recognition.closure_min_evidence * step.self_evidence;
  step.closure = step.best.edge >= 0 && step.best.value > options_.closure_threshold && seen && recognised;
  proposed_ = true;
  proposed_restart_ = restart;
  proposed_node_ = step.node;
  proposed_u_ = u;
  return step;
}

void CatGraphFilter::Weigh(const FrameScore& likelihood, const Pose2& u, bool restart, CatGraphStep& step) {
  // Motion, Eq 1 and Eq 2; weights are normalised among particles on entry.
  // log p(z_k | L_m), once per step for every node a particle touches.
  ++steps_;
  node_ll_.resize(graph_.nodes().size());
  node_ll_step_.resize(graph_.nodes().size(), 0);
  auto own_ll = [&](int n) {
    const auto i = static_cast<std::size_t>(n);
    if (node_ll_step_[i] != steps_) {
      node_ll_step_[i] = steps_;
      node_ll_[i] = likelihood.LogLikelihood(graph_.node(n).observation);
    }
    return node_ll_[i];
  };
  // Eq 2's node likelihood: the node's own, or the mean over the eligible
  // nodes within the observation window along the path.
  if (options_.recognition.observation_window_m > 0.0) {
    window_ll_.resize(graph_.nodes().size());
    window_ll_step_.resize(graph_.nodes().size(), 0);
  }
  auto node_ll = [&](int n) {
    if (options_.recognition.observation_window_m == 0.0) return own_ll(n);
    const auto i = static_cast<std::size_t>(n);
    if (window_ll_step_[i] != steps_) {
      window_ll_step_[i] = steps_;
      const GraphNode& centre = graph_.node(n);
      double sum = own_ll(n);
      int count = 1;
      for (const int step_dir : {-1, 1}) {
        for (int m = n + step_dir; m >= 0 && m < static_cast<int>(graph_.nodes().size()); m += step_dir) {
          const GraphNode& node = graph_.node(m);
          if (std::abs(node.time_s - graph_.node(m - step_dir).time_s) > options_.sequence_break_s ||
              std::abs(node.path_length_m - centre.path_length_m) > options_.recognition.observation_window_m) {
            break;
          }
          if (!Eligible(m)) continue;
          sum = LogSumExp(sum, own_ll(m));
          ++count;
        }
      }
      window_ll_[i] = sum - std::log(static_cast<double>(count));
    }
    return window_ll_[i];
  };
  // Prior mass of new place: p_new while the robot was in a new place, the
  // leave probability while it was on the map, mixed by last step's posterior
  // [D, docs/frontend.md]. The offset, charged to new place in Eq 6 below, is
  // what entering the map costs; once the robot is on it (half the mass or
  // more), staying costs only a fraction of that, so the mass carried on is
  // credited the rest [D, docs/frontend.md "Staying on the map"]. Mass that
  // has just entered is not: else a frame a little under the offset followed
  // by a middling one would enter, as a lagging cloud re-entering does.
  // Staying can also cost a fraction of the frame's self-evidence, never
  // more than entering costs: a frame of a bare wall, with few words, scores
  // little anywhere, the true place included; a frame of a changed place has
  // many words and scores little at the true place only.
  const double self_evidence = likelihood.SelfEvidence();
  step.self_evidence = self_evidence;
  const double offset = options_.new_place.log_offset.value_or(model_.NewPlaceLogOffset());
  // The mass that holds the robot on the map: all of it, or under
  // hold_after_closure none until the cloud has closed since it came on.
  const double held = options_.new_place.hold_after_closure && !closed_since_entry_ ? 0.0 : mapped_mass_;
  const double h = options_.new_place.leave_probability;
  const double prior_new = held * h + (1.0 - held) * options_.new_place_prior;
  double stay_credit = 0.0;
  if (held >= 0.5) {
    stay_credit = (1.0 - options_.new_place.stay_fraction) * offset;
    if (options_.new_place.stay_relative_offset > 0.0) {
      stay_credit = std::max(0.0, stay_credit - options_.new_place.stay_relative_offset * self_evidence);
    }
  }
  const double log_keep =
      stay_credit == 0.0 ? std::log(1.0 - prior_new)
                         : LogSumExp(std::log(held * (1.0 - h)) + stay_credit,
                                     std::log((1.0 - held) * (1.0 - options_.new_place_prior)));
  if (!restart) kernel_.Move(particles_, u, options_.motion_sigma, rng_);
  double log_mixture = kNegInf;  // log sum_i w_i p(z | particle i), for log_evidence
  for (Particle& p : particles_) {
    if (p.log_weight == kNegInf) continue;
    const GraphEdge& e = graph_.edge(p.edge);
    // Direction +1 faces the way the nodes' camera faced (a node's frame is
    // the robot's pose). A forward camera facing the other way sees what the
    // nodes never saw: such a particle is weighed as an unremarkable place,
    // by the model's unseen place (FAB-MAP's mean field; without the new-place offset)
    // [D, docs/frontend.md].
    const bool reversed = options_.recognition.forward_camera && p.direction < 0;
    const double log_observation =
        reversed ? likelihood.LogUnseenPlaceLikelihood()
                 : LogSumExp(p.alpha < 1.0 ? std::log(1.0 - p.alpha) + node_ll(e.from) : kNegInf,
                             p.alpha > 0.0 ? std::log(p.alpha) + node_ll(e.to) : kNegInf);
    log_mixture = LogSumExp(log_mixture, p.log_weight + log_observation);
    p.log_weight += log_observation + log_keep;
  }
  step.log_evidence = log_mixture == kNegInf ? std::numeric_limits<double>::quiet_NaN()
                                             : log_mixture - likelihood.LogNewPlaceLikelihood();
  // New place (Eq 6): mean-field FAB-MAP and the odometry against its mean.
  double log_new = std::log(prior_new) + likelihood.LogNewPlaceLikelihood() + offset;
  if (!restart) {
    // The odometry's running mean.
    ++u_count_;
    u_mean_ += (u.ToVector() - u_mean_) / u_count_;
    log_new += NewPlaceMotionLogLikelihood(u.ToVector(), u_mean_,
                                           options_.new_place.motion_sigma.value_or(options_.motion_sigma));
  }
  double log_total = log_new;
  for (const Particle& p : particles_) log_total = LogSumExp(log_total, p.log_weight);
  for (Particle& p : particles_) p.log_weight -= log_total;
  step.new_place_probability = std::exp(log_new - log_total);
  mapped_mass_ = particles_.empty() ? 0.0 : 1.0 - step.new_place_probability;
  if (mapped_mass_ < 0.5) closed_since_entry_ = false;  // off the map: the next entry starts afresh
}

LocationHypothesis CatGraphFilter::PutParticlesAt(int node, int newest) {
  // The start of the node's edge to its successor (the end of the edge
  // from its predecessor for the newest eligible node).
  LocationHypothesis at{-1, 0.0, 1, 1.0};
  for (const int e : graph_.node(node).edges) {
    const GraphEdge& edge = graph_.edge(e);
    if (edge.type != EdgeType::kOdometry || edge.from == newest || edge.to == newest) continue;
    if (edge.from == node) at.edge = e, at.alpha = 0.0;
    if (edge.to == node && at.edge < 0) at.edge = e, at.alpha = 1.0;
  }
  if (at.edge < 0) throw std::invalid_argument("CatGraphFilter: aliasing onto a node without odometry edges");
  const double log_weight = -std::log(static_cast<double>(options_.num_particles));
  particles_.assign(static_cast<std::size_t>(options_.num_particles), {at.edge, at.alpha, 1, log_weight});
  return at;
}

void CatGraphFilter::Commit(CatGraphStep& step, const ClosureOverride& decision) {
  if (!proposed_ || step.node != proposed_node_) {
    throw std::logic_error("CatGraphFilter: Commit of a step that was not the last proposed");
  }
  if (decision.force_node >= eligible_below_) {
    throw std::invalid_argument("CatGraphFilter: aliasing onto node " + std::to_string(decision.force_node) +
                                ", which is not older than the exclusion windows");
  }
  if (decision.force_node >= 0) {
    step.best = PutParticlesAt(decision.force_node, step.node);
    step.new_place_probability = 0.0;
    mapped_mass_ = 1.0;
  }
  proposed_ = false;
  step.closure = decision.force_node >= 0 || (step.closure && !decision.withhold);
  if (step.closure) {
    std::tie(step.matched_node, step.T_node_matched) = kernel_.LoopTo(step.best);
    step.loop_edge = graph_.AddEdge(step.node, step.matched_node, step.T_node_matched, EdgeType::kVisualLoop);
    // A closure the back end rejected is no recognition: it does not hold
    // the cloud where it put it (docs/frontend.md "Held after a closure").
    closed_since_entry_ = mapped_mass_ >= 0.5 && !decision.vetoed;
  }
  step.resampled = Resample();
  if (options_.inference.enabled) {
    inference_.Step(step.node, proposed_restart_ ? Pose2() : proposed_u_, step.closure && !decision.vetoed, step.best,
                    particles_, eligible_below_, step.inference);
  }
}

bool CatGraphFilter::Resample() {
  const double n = static_cast<double>(options_.num_particles);
  if (particles_.empty() || EffectiveSampleSize(particles_) / n < options_.ess_threshold) {
    // Draws beyond the particles' mass are new-place draws (weights are
    // normalised jointly with the new place).
    std::size_t new_places = static_cast<std::size_t>(options_.num_particles);
    std::vector<Particle> next = SystematicResample(particles_, options_.num_particles, rng_, &new_places);
    SeedUniformly(new_places, next);
    for (Particle& p : next) p.log_weight = -std::log(static_cast<double>(next.size()));
    particles_ = std::move(next);
    return true;
  }
  double sum = 0.0;
  for (const Particle& p : particles_) sum += std::exp(p.log_weight);
  for (Particle& p : particles_) p.log_weight -= std::log(sum);  // normalised among particles
  return false;
}

}  // namespace catgraph
