#include "frontend/cat_graph.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <stdexcept>
#include <string>

namespace catgraph {
namespace {

constexpr double kNegInf = -std::numeric_limits<double>::infinity();

double LogSumExp(double a, double b) {
  if (a == kNegInf) return b;
  if (b == kNegInf) return a;
  const double m = std::max(a, b);
  return m + std::log(std::exp(a - m) + std::exp(b - m));
}

}  // namespace

void Validate(const CatGraphOptions& o) {
  auto fail = [](const std::string& what) { throw std::invalid_argument("CatGraphOptions: " + what); };
  if (o.num_particles < 1) fail("num_particles must be >= 1");
  if (!(o.closure_threshold > 0.0 && o.closure_threshold <= 1.0)) fail("closure_threshold must be in (0, 1]");
  if (!(o.hypothesis_radius_m > 0.0)) fail("hypothesis_radius_m must be > 0");
  if (!(o.motion_sigma.minCoeff() > 0.0)) fail("motion_sigma must be > 0");
  if (!(o.ess_threshold > 0.0 && o.ess_threshold <= 1.0)) fail("ess_threshold must be in (0, 1]");
  if (!(o.new_place_prior > 0.0 && o.new_place_prior < 1.0)) fail("new_place_prior must be in (0, 1)");
  if (!(o.exclusion_window_s >= 0.0 && o.exclusion_window_m >= 0.0)) fail("exclusion windows must be >= 0");
  if (!(o.motion_radius_m > 0.0)) fail("motion_radius_m must be > 0");
}

CatGraphFilter::CatGraphFilter(const FabMapModel& model, CatGraphOptions options)
    : model_(model), options_(options), rng_(options.seed) {
  Validate(options_);
}

bool CatGraphFilter::Eligible(int node) const {
  const GraphNode& n = graph_.node(node);
  return time_s_ - n.time_s >= options_.exclusion_window_s &&
         path_length_m_ - n.path_length_m >= options_.exclusion_window_m;
}

void CatGraphFilter::SeedUniformly(std::size_t count, std::vector<Particle>& out) {
  // Eligible, non-degenerate edges, drawn in proportion to their length.
  std::vector<int> edges;
  std::vector<double> cumulative;
  for (std::size_t id = 0; id < graph_.edges().size(); ++id) {
    const GraphEdge& e = graph_.edges()[id];
    if (e.length_m < 1e-6 || !Eligible(e.from) || !Eligible(e.to)) continue;
    edges.push_back(static_cast<int>(id));
    cumulative.push_back((cumulative.empty() ? 0.0 : cumulative.back()) + e.length_m);
  }
  if (edges.empty()) return;
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (std::size_t i = 0; i < count; ++i) {
    const double r = unit(rng_) * cumulative.back();
    const auto k = static_cast<std::size_t>(std::upper_bound(cumulative.begin(), cumulative.end(), r) -
                                            cumulative.begin());
    out.push_back({edges[std::min(k, edges.size() - 1)], unit(rng_), unit(rng_) < 0.5 ? 1 : -1, 0.0});
  }
}

// Moves one particle by u plus noise in its edge's local graph and projects
// it back; returns log Eq 1 (−inf when there is nowhere to project).
double CatGraphFilter::MotionAndProjection(Particle& p, const Pose2& u) {
  const GraphEdge& e = graph_.edge(p.edge);
  auto it = motion_graphs_.find(e.from);
  if (it == motion_graphs_.end()) {
    it = motion_graphs_
             .emplace(e.from, BuildLocalGraph(graph_, e.from, options_.motion_radius_m + e.length_m,
                                              [this](int n) { return Eligible(n); }))
             .first;
  }
  const LocalGraph& local = it->second;
  if (!local.Contains(e.to)) return kNegInf;
  Pose2 x = local.PointPose(graph_, p.edge, p.alpha);
  if (p.direction < 0) x = x * Pose2(0.0, 0.0, std::numbers::pi);
  const Eigen::Vector3d& s = options_.motion_sigma;
  std::normal_distribution<double> normal(0.0, 1.0);
  const Pose2 noisy(u.x() + s[0] * normal(rng_), u.y() + s[1] * normal(rng_), u.theta() + s[2] * normal(rng_));
  const Pose2 y = x * noisy;
  const auto projection = ProjectOntoLocalGraph(graph_, local, y);
  if (!projection) return kNegInf;
  const double path_heading = projection->pose.theta();
  const int direction = std::abs(WrapAngle(y.theta() - path_heading)) <= std::numbers::pi / 2 ? 1 : -1;
  const double heading = direction > 0 ? path_heading : path_heading + std::numbers::pi;
  p = {projection->edge, projection->alpha, direction, p.log_weight};
  const double dx = projection->pose.x() - y.x(), dy = projection->pose.y() - y.y();
  double m = dx * dx / (s[0] * s[0]) + dy * dy / (s[1] * s[1]);
  if (options_.heading_in_position_likelihood) {
    const double dt = WrapAngle(heading - y.theta());
    m += dt * dt / (s[2] * s[2]);
  }
  return -0.5 * m;
}

LocationHypothesis CatGraphFilter::BestHypothesis() const {
  LocationHypothesis best;
  if (particles_.empty()) return best;
  // Eq 4 at every particle is O(n_p²); candidates are instead the heaviest
  // particle of every 0.1 m stretch of each occupied edge.
  std::map<int, std::vector<std::size_t>> by_edge;
  for (std::size_t i = 0; i < particles_.size(); ++i) {
    if (particles_[i].log_weight > -std::numeric_limits<double>::infinity()) by_edge[particles_[i].edge].push_back(i);
  }
  const double r = options_.hypothesis_radius_m;
  for (const auto& [edge, members] : by_edge) {
    const GraphEdge& e = graph_.edge(edge);
    std::map<int, std::size_t> candidates;  // bin -> particle
    for (const std::size_t i : members) {
      const int bin = static_cast<int>(particles_[i].alpha * e.length_m / 0.1);
      auto [it, inserted] = candidates.try_emplace(bin, i);
      if (!inserted && particles_[i].log_weight > particles_[it->second].log_weight) it->second = i;
    }
    // Every particle that can lie within r of a point of this edge; only
    // eligible nodes, so that the location never lands on a recent node
    // reached through a loop edge.
    const LocalGraph local = BuildLocalGraph(graph_, e.from, r + e.length_m + 1e-6,
                                             [this](int n) { return Eligible(n); });
    std::vector<std::pair<Eigen::Vector2d, double>> nearby;
    for (const int other : local.edges) {
      const auto it = by_edge.find(other);
      if (it == by_edge.end()) continue;
      for (const std::size_t j : it->second) {
        nearby.emplace_back(local.PointPose(graph_, other, particles_[j].alpha).translation(),
                            std::exp(particles_[j].log_weight));
      }
    }
    for (const auto& [bin, i] : candidates) {
      const Eigen::Vector2d c = local.PointPose(graph_, edge, particles_[i].alpha).translation();
      double sum = 0.0;
      Eigen::Vector2d mean = Eigen::Vector2d::Zero();
      for (const auto& [q, w] : nearby) {
        if ((q - c).squaredNorm() <= r * r) sum += w, mean += w * q;
      }
      if (sum <= best.value) continue;
      // Eq 4 is flat over every candidate whose d_h-disc holds the cloud, so
      // the argmax alone can sit up to d_h off; the location reported is the
      // weighted mean of the particles in the winning disc, projected back
      // onto the graph [D, docs/frontend.md].
      best = {edge, particles_[i].alpha, particles_[i].direction, sum};
      if (sum > 0.0) {
        const Pose2 centre(mean.x() / sum, mean.y() / sum, 0.0);
        if (const auto p = ProjectOntoLocalGraph(graph_, local, centre)) {
          best.edge = p->edge;
          best.alpha = p->alpha;
        }
      }
    }
  }
  return best;
}

CatGraphStep CatGraphFilter::Step(int frame, double time_s, const Pose2& u, const WordSet& words) {
  const bool first = graph_.nodes().empty();
  time_s_ = time_s;
  if (!first) path_length_m_ += u.translation().norm();
  motion_graphs_.clear();
  CatGraphStep step;
  const FrameLikelihood likelihood = model_.ForFrame(words);

  if (particles_.empty()) {
    SeedUniformly(static_cast<std::size_t>(options_.num_particles), particles_);
    for (Particle& p : particles_) p.log_weight = -std::log(static_cast<double>(particles_.size()));
  }
  // Motion, Eq 1 and Eq 2; weights are normalised among particles on entry.
  std::unordered_map<int, double> node_log_likelihood;
  auto node_ll = [&](int n) {
    auto [it, inserted] = node_log_likelihood.try_emplace(n, 0.0);
    if (inserted) it->second = likelihood.LogLikelihood(graph_.node(n).words);
    return it->second;
  };
  const double log_keep = std::log(1.0 - options_.new_place_prior);
  for (Particle& p : particles_) {
    const double log_motion = first ? 0.0 : MotionAndProjection(p, u);
    if (log_motion == kNegInf) {
      p.log_weight = kNegInf;
      continue;
    }
    const GraphEdge& e = graph_.edge(p.edge);
    const double log_observation =
        LogSumExp(p.alpha < 1.0 ? std::log(1.0 - p.alpha) + node_ll(e.from) : kNegInf,
                  p.alpha > 0.0 ? std::log(p.alpha) + node_ll(e.to) : kNegInf);
    p.log_weight += log_motion + log_observation + log_keep;
  }
  // New place (Eq 6): mean-field FAB-MAP and the odometry against its mean.
  if (!first) {
    u_sum_ += u.ToVector();
    ++u_count_;
  }
  const Eigen::Vector3d u_mean = u_count_ > 0 ? Eigen::Vector3d(u_sum_ / u_count_) : Eigen::Vector3d::Zero();
  const Eigen::Vector3d du = (u.ToVector() - u_mean).cwiseQuotient(options_.motion_sigma);
  const double log_new = std::log(options_.new_place_prior) + likelihood.LogNewPlaceLikelihood() -
                         0.5 * du.squaredNorm();
  double log_total = log_new;
  for (const Particle& p : particles_) log_total = LogSumExp(log_total, p.log_weight);
  for (Particle& p : particles_) p.log_weight -= log_total;
  step.new_place_probability = std::exp(log_new - log_total);

  // Location hypothesis and loop closure (Eq 4).
  step.best = BestHypothesis();
  const int previous = first ? -1 : static_cast<int>(graph_.nodes().size()) - 1;
  step.node = graph_.AddNode(frame, time_s, path_length_m_, words);
  if (previous >= 0) graph_.AddEdge(previous, step.node, u, EdgeType::kOdometry);
  if (step.best.edge >= 0 && step.best.value > options_.closure_threshold) {
    const GraphEdge& e = graph_.edge(step.best.edge);
    const LocalGraph local = BuildLocalGraph(graph_, e.from, e.length_m + 1e-6, {});
    Pose2 x = local.PointPose(graph_, step.best.edge, step.best.alpha);
    if (step.best.direction < 0) x = x * Pose2(0.0, 0.0, std::numbers::pi);
    step.closure = true;
    step.matched_node = step.best.alpha < 0.5 ? e.from : e.to;
    step.T_node_matched = x.Between(local.pose.at(step.matched_node));
    step.loop_edge = graph_.AddEdge(step.node, step.matched_node, step.T_node_matched, EdgeType::kVisualLoop);
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
    std::vector<Particle> next;
    next.reserve(particles_.size());
    std::size_t new_places = 0;
    if (!particles_.empty()) {
      const double spacing = 1.0 / n;
      double u0 = std::uniform_real_distribution<double>(0.0, spacing)(rng_);
      double cumulative = 0.0;
      std::size_t i = 0;
      for (int k = 0; k < options_.num_particles; ++k, u0 += spacing) {
        while (i < particles_.size() && cumulative + std::exp(particles_[i].log_weight) < u0) {
          cumulative += std::exp(particles_[i].log_weight);
          ++i;
        }
        if (i < particles_.size()) next.push_back(particles_[i]);
        else ++new_places;
      }
    } else {
      new_places = static_cast<std::size_t>(options_.num_particles);
    }
    SeedUniformly(new_places, next);
    for (Particle& p : next) p.log_weight = -std::log(static_cast<double>(next.size()));
    particles_ = std::move(next);
    step.resampled = true;
  } else {
    for (Particle& p : particles_) p.log_weight -= std::log(sum);  // normalised among particles
  }
  return step;
}

}  // namespace catgraph
