#include "frontend/cat_graph.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "backend/graph/name_table.h"

namespace catgraph {
namespace {

constexpr double kNegInf = -std::numeric_limits<double>::infinity();

double LogSumExp(double a, double b) {
  if (a == kNegInf) return b;
  if (b == kNegInf) return a;
  const double m = std::max(a, b);
  return m + std::log(std::exp(a - m) + std::exp(b - m));
}

// Systematic resampling of n draws over the particles' weights (which may sum
// to less than 1); draws past the last particle are counted in *beyond.
std::vector<Particle> SystematicResample(const std::vector<Particle>& particles, int n, std::mt19937_64& rng,
                                         std::size_t* beyond) {
  std::vector<Particle> next;
  next.reserve(static_cast<std::size_t>(n));
  *beyond = 0;
  if (particles.empty()) {
    *beyond = static_cast<std::size_t>(n);
    return next;
  }
  const double spacing = 1.0 / n;
  double u0 = std::uniform_real_distribution<double>(0.0, spacing)(rng);
  double cumulative = 0.0;
  std::size_t i = 0;
  for (int k = 0; k < n; ++k, u0 += spacing) {
    while (i < particles.size() && cumulative + std::exp(particles[i].log_weight) < u0) {
      cumulative += std::exp(particles[i].log_weight);
      ++i;
    }
    if (i < particles.size()) {
      next.push_back(particles[i]);
    } else {
      ++*beyond;
    }
  }
  return next;
}

}  // namespace

bool IsValidSigma(const Eigen::Vector3d& sigma) { return (sigma.array() > 0.0).all() && sigma.allFinite(); }

void Validate(const CatGraphOptions& o) {
  auto fail = [](const std::string& what) { throw std::invalid_argument("CatGraphOptions: " + what); };
  if (o.num_particles < 1 || o.num_particles > kMaxParticles) {
    fail("num_particles must be from 1 to " + std::to_string(kMaxParticles));
  }
  if (!(o.closure_threshold > 0.0 && o.closure_threshold <= 1.0)) fail("closure_threshold must be in (0, 1]");
  if (!(o.hypothesis_radius_m > 0.0)) fail("hypothesis_radius_m must be > 0");
  if (!IsValidSigma(o.motion_sigma)) fail("motion_sigma must be finite and > 0");
  if (!(o.ess_threshold > 0.0 && o.ess_threshold <= 1.0)) fail("ess_threshold must be in (0, 1]");
  if (!(o.new_place_prior > 0.0 && o.new_place_prior < 1.0)) fail("new_place_prior must be in (0, 1)");
  if (!(o.exclusion_window_s >= 0.0)) fail("exclusion_window_s must be >= 0");
  if (!(o.exclusion_window_m >= 0.0)) fail("exclusion_window_m must be >= 0");
  if (!(o.sequence_break_s > 0.0)) fail("sequence_break_s must be > 0");
  if (!(o.motion_radius_m > 0.0)) fail("motion_radius_m must be > 0");
  if (o.hypothesis_candidate_edges < 1) fail("hypothesis_candidate_edges must be >= 1");

  const RecognitionOptions& r = o.recognition;
  if (!(r.closure_min_evidence >= 0.0 && r.closure_min_evidence <= 1.0)) {
    fail("recognition.closure_min_evidence must be in [0, 1]");
  }
  if (!(r.observation_window_m >= 0.0 && std::isfinite(r.observation_window_m))) {
    fail("recognition.observation_window_m must be finite and >= 0");
  }

  const NewPlaceOptions& n = o.new_place;
  if (n.log_offset && !std::isfinite(*n.log_offset)) fail("new_place.log_offset must be finite");
  if (!(n.leave_probability > 0.0 && n.leave_probability < 1.0)) fail("new_place.leave_probability must be in (0, 1)");
  if (!(n.stay_fraction >= 0.0 && n.stay_fraction <= 1.0)) fail("new_place.stay_fraction must be in [0, 1]");
  if (!(n.stay_relative_offset >= 0.0 && n.stay_relative_offset < 1.0)) {
    fail("new_place.stay_relative_offset must be in [0, 1)");
  }
  if (n.motion_sigma && !IsValidSigma(*n.motion_sigma)) fail("new_place.motion_sigma must be finite and > 0");

  if (!(o.gate.base_m >= 0.0 && o.gate.fraction >= 0.0)) fail("gate.base_m and gate.fraction must be >= 0");

  const InferenceOptions& i = o.inference;
  if (!(i.local_validation_m > 0.0)) fail("inference.local_validation_m (d_loc) must be > 0");
  if (!(i.total_validation_m > 0.0)) fail("inference.total_validation_m (d_tot) must be > 0");
  if (!(i.total_path_retries >= 0 && i.total_path_retries <= 100)) {
    fail("inference.total_path_retries must be in [0, 100]");
  }
  if (!(i.particle_factor >= 1 && i.particle_factor <= 100)) fail("inference.particle_factor must be in [1, 100]");
  if (i.motion_sigma && !IsValidSigma(*i.motion_sigma)) fail("inference.motion_sigma must be finite and > 0");
}

CatGraphOptions CatGraphOptions::Paper() {
  CatGraphOptions o;
  o.motion_sigma = Eigen::Vector3d(0.05, 0.05, 0.005);
  o.recognition = {.closure_min_evidence = 0.0, .forward_camera = false, .observation_window_m = 0.0};
  // One prior for new place whether or not the robot is on the map, and one
  // likelihood: Eq 6 as written, weighed by Q.
  o.new_place = {.log_offset = 0.0,
                 .leave_probability = o.new_place_prior,
                 .stay_fraction = 1.0,
                 .stay_relative_offset = 0.0,
                 .hold_after_closure = false,
                 .motion_sigma = std::nullopt};
  o.gate.enabled = false;
  o.inference = {.enabled = true,
                 .local_validation_m = 2.0,
                 .total_validation_m = 1.0,
                 .total_path_retries = 0,
                 .seed_local = false,
                 .particle_factor = 1,
                 .motion_sigma = std::nullopt};
  return o;
}

CatGraphFilter::CatGraphFilter(const ObservationModel& model, CatGraphOptions options)
    : model_(model),
      options_(options),
      rng_(options.seed),
      eligible_([this](int n) { return Eligible(n); }),
      odometric_rng_(options.seed ^ 0x9E3779B97F4A7C15ULL) {
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

double PositionLogLikelihood(const Pose2& start, const Pose2& y, const Pose2& x, const Eigen::Vector3d& sigma,
                             bool with_heading) {
  // x - y along (first) and across (second) the start pose's heading.
  const Eigen::Vector2d d = start.rotation().transpose() * (x.translation() - y.translation());
  double m = d.x() * d.x() / (sigma[0] * sigma[0]) + d.y() * d.y() / (sigma[1] * sigma[1]);
  if (with_heading) {
    const double dt = WrapAngle(x.theta() - y.theta());
    m += dt * dt / (sigma[2] * sigma[2]);
  }
  return -0.5 * m;
}

double NewPlaceMotionLogLikelihood(const Eigen::Vector3d& u, const Eigen::Vector3d& mean,
                                   const Eigen::Vector3d& sigma) {
  return -0.5 * (u - mean).cwiseQuotient(sigma).squaredNorm();
}


double OdometricGateRadius(const CatGraphOptions& options, double path_since_m) {
  if (!options.gate.enabled) return std::numeric_limits<double>::infinity();
  return options.gate.base_m + options.gate.fraction * path_since_m;
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

void CatGraphFilter::MotionAndProjection(std::vector<Particle>& particles, const Pose2& u,
                                         const Eigen::Vector3d& sigma, std::mt19937_64& rng) {
  // Particles in order of their edge's start node, so that each local graph
  // is built once per step.
  order_.resize(particles.size());
  for (std::size_t i = 0; i < order_.size(); ++i) order_[i] = i;
  auto anchor = [&](std::size_t i) { return graph_.edge(particles[i].edge).from; };
  std::stable_sort(order_.begin(), order_.end(), [&](std::size_t a, std::size_t b) { return anchor(a) < anchor(b); });
  std::normal_distribution<double> normal(0.0, 1.0);
  // The local graph must hold wherever a particle can go this step: at least
  // the step plus four σ (frames far apart: real image sets).
  const double radius = std::max(options_.motion_radius_m, u.translation().norm() + 4.0 * sigma.head<2>().maxCoeff());
  int built = -1;
  for (const std::size_t i : order_) {
    Particle& p = particles[i];
    const GraphEdge& e = graph_.edge(p.edge);
    if (e.from != built) {
      builder_.Build(graph_, e.from, radius + e.length_m, eligible_, local_);
      built = e.from;
    }
    const std::optional<Pose2> start = local_.PointPose(p.edge, p.alpha);
    if (!start) {  // the edge's end is no longer eligible
      p.log_weight = kNegInf;
      continue;
    }
    const Pose2 x = p.direction < 0 ? *start * Pose2(0.0, 0.0, std::numbers::pi) : *start;
    // One draw per statement: a call's arguments are evaluated in an
    // unspecified order, and a seed must give the same particles with every
    // compiler (heading first: the order GCC used, so results stay as measured).
    const double w_theta = sigma[2] * normal(rng), w_y = sigma[1] * normal(rng), w_x = sigma[0] * normal(rng);
    const Pose2 noisy(u.x() + w_x, u.y() + w_y, u.theta() + w_theta);
    const Pose2 y = x * noisy;
    const auto projection = ProjectOntoLocalGraph(local_, y);
    if (!projection) {
      p.log_weight = kNegInf;
      continue;
    }
    const double path_heading = projection->pose.theta();
    const int direction = std::abs(WrapAngle(y.theta() - path_heading)) <= std::numbers::pi / 2 ? 1 : -1;
    const double heading = direction > 0 ? path_heading : path_heading + std::numbers::pi;
    p.edge = projection->edge;
    p.alpha = projection->alpha;
    p.direction = direction;
    p.log_weight += PositionLogLikelihood(x, y, Pose2(projection->pose.x(), projection->pose.y(), heading), sigma,
                                          options_.heading_in_position_likelihood);
  }
}

LocationHypothesis CatGraphFilter::BestHypothesis(const std::vector<Particle>& particles) {
  LocationHypothesis best;
  // Particles grouped by edge, with each edge's total weight.
  order_.clear();
  for (std::size_t i = 0; i < particles.size(); ++i) {
    if (particles[i].log_weight > kNegInf) order_.push_back(i);
  }
  if (order_.empty()) return best;
  std::stable_sort(order_.begin(), order_.end(),
                   [&](std::size_t a, std::size_t b) { return particles[a].edge < particles[b].edge; });
  struct EdgeGroup {
    int edge;
    std::size_t begin, end;  // range in order_
    double weight;
  };
  std::vector<EdgeGroup> groups;
  weight_.resize(order_.size());  // the particles' weights, in order_
  for (std::size_t k = 0; k < order_.size(); ++k) {
    const Particle& p = particles[order_[k]];
    if (groups.empty() || groups.back().edge != p.edge) groups.push_back({p.edge, k, k, 0.0});
    groups.back().end = k + 1;
    weight_[k] = std::exp(p.log_weight);
    groups.back().weight += weight_[k];
  }
  auto group_of = [&](int edge) -> const EdgeGroup* {
    const auto it = std::lower_bound(groups.begin(), groups.end(), edge,
                                     [](const EdgeGroup& g, int id) { return g.edge < id; });
    return it != groups.end() && it->edge == edge ? &*it : nullptr;
  };
  // Eq 4 at every particle is O(n_p²). Candidates are the heaviest particle
  // of every 0.1 m stretch of the heaviest edges: a disc holding mass T_h
  // spread over M edges has an edge of weight >= T_h / M, so it is among the
  // K heaviest whenever K > M (1 - T_h) / T_h (docs/frontend.md).
  std::vector<const EdgeGroup*> candidates;
  for (const EdgeGroup& g : groups) candidates.push_back(&g);
  const auto k = std::min(candidates.size(), static_cast<std::size_t>(options_.hypothesis_candidate_edges));
  std::partial_sort(candidates.begin(), candidates.begin() + static_cast<long>(k), candidates.end(),
                    [](const EdgeGroup* a, const EdgeGroup* b) {
                      return a->weight > b->weight || (a->weight == b->weight && a->edge < b->edge);
                    });
  candidates.resize(k);

  const double r = options_.hypothesis_radius_m;
  struct Nearby {
    Eigen::Vector2d position;
    double weight;
    int direction;
  };
  std::vector<Nearby> nearby;
  std::map<int, std::size_t> bins;  // 0.1 m bin -> heaviest particle
  for (const EdgeGroup* g : candidates) {
    const GraphEdge& e = graph_.edge(g->edge);
    bins.clear();
    for (std::size_t q = g->begin; q < g->end; ++q) {
      const std::size_t i = order_[q];
      const int bin = static_cast<int>(particles[i].alpha * e.length_m / 0.1);
      auto [it, inserted] = bins.try_emplace(bin, i);
      if (!inserted && particles[i].log_weight > particles[it->second].log_weight) it->second = i;
    }
    // Every particle that can lie within r of a point of this edge; only
    // eligible nodes, so that the location never lands on a recent node
    // reached through a loop edge.
    builder_.Build(graph_, e.from, r + e.length_m + 1e-6, eligible_, local_);
    nearby.clear();
    for (const LocalGraph::Segment& s : local_.segments) {
      const EdgeGroup* other = group_of(s.edge);
      if (other == nullptr) continue;
      for (std::size_t q = other->begin; q < other->end; ++q) {
        const Particle& p = particles[order_[q]];
        nearby.push_back({InterpolateTranslation(s.from, s.to, p.alpha), weight_[q], p.direction});
      }
    }
    for (const auto& [bin, i] : bins) {
      const Eigen::Vector2d c = local_.PointPose(g->edge, particles[i].alpha)->translation();
      double sum = 0.0, forward = 0.0;
      Eigen::Vector2d mean = Eigen::Vector2d::Zero();
      for (const Nearby& q : nearby) {
        if ((q.position - c).squaredNorm() > r * r) continue;
        sum += q.weight;
        mean += q.weight * q.position;
        forward += q.direction > 0 ? q.weight : 0.0;
      }
      if (sum <= best.value) continue;
      // Eq 4 is flat over every candidate whose d_h-disc holds the cloud, so
      // the argmax alone can sit up to d_h off; the location reported is the
      // weighted mean of the particles in the winning disc, projected back
      // onto the graph, facing the way most of their weight faces (after
      // resampling every weight is equal, and the candidate particle's own
      // direction would be anyone's) [D, docs/frontend.md].
      best = {g->edge, particles[i].alpha, forward >= 0.5 * sum ? 1 : -1, sum};
      if (const auto p = ProjectOntoLocalGraph(local_, Pose2(mean.x() / sum, mean.y() / sum, 0.0))) {
        best.edge = p->edge;
        best.alpha = p->alpha;
      }
    }
  }
  return best;
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

CatGraphStep CatGraphFilter::Step(int frame, double time_s, const Pose2& u, const Observation& z,
                                  const Aliasing& aliasing) {
  const bool first = graph_.nodes().empty();
  // After a gap in the frames (traversals recorded apart) the motion since
  // the previous frame says nothing about where the particles went: they are
  // seeded afresh and the motion terms are left out for this frame.
  const bool restart = first || time_s - time_s_ > options_.sequence_break_s;
  // Pending inferences a restart drops, reported with this step.
  std::vector<InferredClosure> lost;
  int lost_reference = -1;
  if (restart && !first) {
    particles_.clear();
    odometric_.clear();  // CAT-Graph+ waits for the next visual closure
    lost_reference = reference_node_;
    reference_node_ = -1;
    lost = std::move(pending_);
    pending_.clear();
    closed_since_entry_ = false;
  }
  time_s_ = time_s;
  if (!first) path_length_m_ += u.translation().norm();
  if (!first) odometry_pose_ = odometry_pose_ * u;
  eligible_below_ = EligibleBelow();
  if (aliasing.false_match >= eligible_below_) {
    throw std::invalid_argument("CatGraphFilter: aliasing onto node " + std::to_string(aliasing.false_match) +
                                ", which is not older than the exclusion windows");
  }
  CatGraphStep step;
  if (!lost.empty()) {
    step.reference_node = lost_reference;
    step.lost = std::move(lost);
    step.lost_reason = DiscardReason::kSequenceBreak;
  }
  const std::unique_ptr<FrameScore> likelihood = model_.ScoreFrame(z, PlacesForScoring());

  if (particles_.empty()) {
    SeedUniformly(static_cast<std::size_t>(options_.num_particles), particles_);
    for (Particle& p : particles_) p.log_weight = -std::log(static_cast<double>(particles_.size()));
  }
  // Motion, Eq 1 and Eq 2; weights are normalised among particles on entry.
  // log p(z_k | L_m), once per step for every node a particle touches.
  ++steps_;
  node_ll_.resize(graph_.nodes().size());
  node_ll_step_.resize(graph_.nodes().size(), 0);
  auto own_ll = [&](int n) {
    const auto i = static_cast<std::size_t>(n);
    if (node_ll_step_[i] != steps_) {
      node_ll_step_[i] = steps_;
      node_ll_[i] = likelihood->LogLikelihood(graph_.node(n).observation);
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
  const double self_evidence = likelihood->SelfEvidence();
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
  if (!restart) MotionAndProjection(particles_, u, options_.motion_sigma, rng_);
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
        reversed ? likelihood->LogUnseenPlaceLikelihood()
                 : LogSumExp(p.alpha < 1.0 ? std::log(1.0 - p.alpha) + node_ll(e.from) : kNegInf,
                             p.alpha > 0.0 ? std::log(p.alpha) + node_ll(e.to) : kNegInf);
    log_mixture = LogSumExp(log_mixture, p.log_weight + log_observation);
    p.log_weight += log_observation + log_keep;
  }
  step.log_evidence = log_mixture == kNegInf ? std::numeric_limits<double>::quiet_NaN()
                                             : log_mixture - likelihood->LogNewPlaceLikelihood();
  // New place (Eq 6): mean-field FAB-MAP and the odometry against its mean.
  double log_new = std::log(prior_new) + likelihood->LogNewPlaceLikelihood() + offset;
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

  // Location hypothesis and loop closure (Eq 4).
  step.best = BestHypothesis(particles_);
  if (aliasing.false_match >= 0) {
    // The start of the node's edge to its successor (the end of the edge
    // from its predecessor for the newest node).
    const int node = aliasing.false_match;
    LocationHypothesis at{-1, 0.0, 1, 1.0};
    for (const int e : graph_.node(node).edges) {
      const GraphEdge& edge = graph_.edge(e);
      if (edge.type != EdgeType::kOdometry) continue;
      if (edge.from == node) at.edge = e, at.alpha = 0.0;
      if (edge.to == node && at.edge < 0) at.edge = e, at.alpha = 1.0;
    }
    if (at.edge < 0) throw std::invalid_argument("CatGraphFilter: aliasing onto a node without odometry edges");
    const double log_weight = -std::log(static_cast<double>(options_.num_particles));
    particles_.assign(static_cast<std::size_t>(options_.num_particles), {at.edge, at.alpha, 1, log_weight});
    step.best = at;
    step.new_place_probability = 0.0;
    mapped_mass_ = 1.0;
  }
  const int previous = first ? -1 : static_cast<int>(graph_.nodes().size()) - 1;
  step.node = graph_.AddNode(frame, time_s, path_length_m_, odometry_pose_, z);
  if (previous >= 0) graph_.AddEdge(previous, step.node, u, EdgeType::kOdometry);
  // A forward camera facing against the matched nodes saw none of what they
  // saw: its particles carry no visual evidence (the mean field above), only
  // the odometry's, and their hypothesis is no visual closure.
  const bool seen = !(options_.recognition.forward_camera && step.best.direction < 0);
  // Nor is a cloud that scores little on what the camera sees (NaN, no
  // particle on the map, fails too).
  const bool recognised =
      options_.recognition.closure_min_evidence == 0.0 || step.log_evidence >= options_.recognition.closure_min_evidence * self_evidence;
  const bool confident = step.best.edge >= 0 && step.best.value > options_.closure_threshold && seen && recognised;
  if (aliasing.false_match >= 0 || (confident && !aliasing.withhold_closure)) {
    step.closure = true;
    std::tie(step.matched_node, step.T_node_matched) = LoopTo(step.best);
    step.loop_edge = graph_.AddEdge(step.node, step.matched_node, step.T_node_matched, EdgeType::kVisualLoop);
    // A closure the back end rejected is no recognition: it does not hold
    // the cloud where it put it (docs/frontend.md "Held after a closure").
    closed_since_entry_ = mapped_mass_ >= 0.5 && !aliasing.vetoed;
  }

  // ESS among the particles (Eq 5); resample with new-place reseeding.
  double sum = 0.0, sum_sq = 0.0;
  for (const Particle& p : particles_) {
    const double w = std::exp(p.log_weight);
    sum += w;
    sum_sq += w * w;
  }
  const double n = static_cast<double>(options_.num_particles);
  const double ess = sum > 0.0 ? sum * sum / sum_sq : 0.0;
  if (particles_.empty() || ess / n < options_.ess_threshold) {
    // Draws beyond the particles' mass are new-place draws (weights are
    // normalised jointly with the new place).
    std::size_t new_places = static_cast<std::size_t>(options_.num_particles);
    std::vector<Particle> next = SystematicResample(particles_, options_.num_particles, rng_, &new_places);
    SeedUniformly(new_places, next);
    for (Particle& p : next) p.log_weight = -std::log(static_cast<double>(next.size()));
    particles_ = std::move(next);
    step.resampled = true;
  } else {
    for (Particle& p : particles_) p.log_weight -= std::log(sum);  // normalised among particles
  }
  if (options_.inference.enabled) OdometricStep(restart ? Pose2() : u, step.closure && !aliasing.vetoed, step);
  return step;
}

std::optional<Pose2> CatGraphFilter::HypothesisPose(const LocationHypothesis& h) const {
  const std::optional<Pose2> x = local_.PointPose(h.edge, h.alpha);
  if (!x || h.direction > 0) return x;
  return *x * Pose2(0.0, 0.0, std::numbers::pi);
}

std::pair<int, Pose2> CatGraphFilter::LoopTo(const LocationHypothesis& h) {
  const GraphEdge& e = graph_.edge(h.edge);
  builder_.Build(graph_, e.from, e.length_m + 1e-6, {}, local_);
  const int matched = h.alpha < 0.5 ? e.from : e.to;
  return {matched, HypothesisPose(h)->Between(local_.PoseOf(matched))};
}

void CatGraphFilter::ReinitialiseOdometric(const LocationHypothesis& match) {
  // §3.5 copies V; here only V's particles within d_h of the match, each
  // copied `odometric_particle_factor` times (CatGraphOptions). The match is
  // the weighted mean of the particles in Eq 4's winning disc, so it has
  // particles near; should none lie within d_h, O is the spec's copy of V.
  std::vector<Particle>& seeds = odometric_seeds_;
  seeds.clear();
  if (options_.inference.seed_local) {
    const GraphEdge& e = graph_.edge(match.edge);
    builder_.Build(graph_, e.from, options_.hypothesis_radius_m + e.length_m + 1e-6, eligible_, local_);
    if (const std::optional<Pose2> centre = local_.PointPose(match.edge, match.alpha)) {
      for (const Particle& p : particles_) {
        if (p.log_weight == kNegInf) continue;
        const std::optional<Pose2> x = local_.PointPose(p.edge, p.alpha);
        if (x && (x->translation() - centre->translation()).norm() <= options_.hypothesis_radius_m) {
          seeds.push_back(p);
        }
      }
    }
  }
  if (seeds.empty()) seeds = particles_;  // the spec's copy of V
  const int factor = options_.inference.particle_factor;
  double log_total = kNegInf;  // each copy weighs w / (factor × the seeds' total)
  for (const Particle& p : seeds) log_total = LogSumExp(log_total, p.log_weight);
  log_total += std::log(static_cast<double>(factor));
  odometric_.clear();
  odometric_.reserve(seeds.size() * static_cast<std::size_t>(factor));
  for (const Particle& p : seeds) {
    for (int k = 0; k < factor; ++k) {
      odometric_.push_back(p);
      odometric_.back().log_weight -= log_total;
    }
  }
}

void CatGraphFilter::OdometricStep(const Pose2& u, bool closure, CatGraphStep& step) {
  if (closure) {
    // Total-path validation (§3.4): the odometric hypothesis against the
    // visual match, in a local graph around the match. O last moved with the
    // previous frame; its hypothesis is carried on by this frame's odometry,
    // so that both are of this frame (y_p'), without drawing O's noise.
    if (reference_node_ >= 0 && !pending_.empty()) {
      const LocationHypothesis odometric = BestHypothesis(odometric_);
      double distance = std::numeric_limits<double>::infinity();
      if (odometric.edge >= 0) {
        const GraphEdge& e = graph_.edge(step.best.edge);
        builder_.Build(graph_, e.from, options_.inference.total_validation_m + e.length_m + 1e-6, eligible_, local_);
        const auto a = local_.PointPose(step.best.edge, step.best.alpha);
        const auto b = HypothesisPose(odometric);
        if (a && b) distance = (a->translation() - (*b * u).translation()).norm();
      }
      if (distance < options_.inference.total_validation_m || total_path_failures_ == options_.inference.total_path_retries) {
        step.reference_node = reference_node_;
        (distance < options_.inference.total_validation_m ? step.inferred : step.discarded) = std::move(pending_);
        pending_.clear();
      } else {
        ++total_path_failures_;  // carried past this closure, as past a vetoed one
      }
    }
    if (pending_.empty()) {
      total_path_failures_ = 0;
      ReinitialiseOdometric(step.best);
      reference_node_ = step.node;
      reference_location_ = step.best;
      T_since_reference_ = Pose2();
      return;
    }
  }
  if (reference_node_ < 0) return;  // no visual closure yet: nothing to infer from

  // The odometric filter: same motion and projection, position-only weights
  // (Eq 8), resampled without new places; Q its own if set.
  MotionAndProjection(odometric_, u, options_.inference.motion_sigma.value_or(options_.motion_sigma), odometric_rng_);
  double log_total = kNegInf;
  for (const Particle& p : odometric_) log_total = LogSumExp(log_total, p.log_weight);
  if (log_total == kNegInf) {  // every particle left the graph: nothing to infer until the next closure
    odometric_.clear();
    if (!pending_.empty()) {
      step.reference_node = reference_node_;
      step.lost = std::move(pending_);
      step.lost_reason = DiscardReason::kFilterLost;
    }
    reference_node_ = -1;
    pending_.clear();
    return;
  }
  double sum_sq = 0.0;
  for (Particle& p : odometric_) {
    p.log_weight -= log_total;
    sum_sq += std::exp(2.0 * p.log_weight);
  }
  if (1.0 / sum_sq < options_.ess_threshold * static_cast<double>(odometric_.size())) {
    std::size_t beyond = 0;
    odometric_ = SystematicResample(odometric_, static_cast<int>(odometric_.size()), odometric_rng_, &beyond);
    for (Particle& p : odometric_) p.log_weight = -std::log(static_cast<double>(odometric_.size()));
  }
  T_since_reference_ = T_since_reference_ * u;
  step.odometric_best = BestHypothesis(odometric_);
  if (step.odometric_best.edge < 0) return;

  // Local validation (§3.3, Eq 9-11): the odometric hypothesis' pose
  // relative to the last visual match, along the old graph's shortest path,
  // against the odometry since then.
  // Through nodes older than the exclusion window only, not through the
  // odometric gate: the gate is about where the robot may be now, and the
  // reference lies behind it.
  const GraphEdge& e = graph_.edge(reference_location_.edge);
  const double radius = T_since_reference_.translation().norm() + options_.inference.local_validation_m + e.length_m;
  builder_.Build(graph_, e.from, radius, [this](int n) { return n < eligible_below_; }, local_);
  const auto from = HypothesisPose(reference_location_);
  const auto to = HypothesisPose(step.odometric_best);
  if (!from || !to) return;
  const Pose2 y = from->Between(*to);
  if ((y.translation() - T_since_reference_.translation()).norm() >= options_.inference.local_validation_m) return;
  step.inference_pending = true;
  InferredClosure c;
  c.node = step.node;
  c.location = step.odometric_best;
  std::tie(c.matched_node, c.T_node_matched) = LoopTo(step.odometric_best);
  pending_.push_back(c);
}

}  // namespace catgraph
