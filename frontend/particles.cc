#include "frontend/particles.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <utility>

namespace catgraph {

double LogSumExp(double a, double b) {
  if (a == kNegInf) return b;
  if (b == kNegInf) return a;
  const double m = std::max(a, b);
  return m + std::log(std::exp(a - m) + std::exp(b - m));
}

double LogTotalWeight(const std::vector<Particle>& particles) {
  double total = kNegInf;
  for (const Particle& p : particles) total = LogSumExp(total, p.log_weight);
  return total;
}

double EffectiveSampleSize(const std::vector<Particle>& particles) {
  double sum = 0.0, sum_sq = 0.0;
  for (const Particle& p : particles) {
    const double w = std::exp(p.log_weight);
    sum += w;
    sum_sq += w * w;
  }
  return sum > 0.0 ? sum * sum / sum_sq : 0.0;
}

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

std::optional<Pose2> HypothesisPose(const LocalGraph& local, const LocationHypothesis& h) {
  const std::optional<Pose2> x = local.PointPose(h.edge, h.alpha);
  if (!x || h.direction > 0) return x;
  return *x * Pose2(0.0, 0.0, std::numbers::pi);
}

ParticleKernel::ParticleKernel(const TrajectoryGraph& graph, Options options, std::function<bool(int)> eligible)
    : graph_(graph), options_(options), eligible_(std::move(eligible)) {}

void ParticleKernel::Move(std::vector<Particle>& particles, const Pose2& u, const Eigen::Vector3d& sigma,
                          std::mt19937_64& rng) {
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

LocationHypothesis ParticleKernel::BestHypothesis(const std::vector<Particle>& particles) {
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

const LocalGraph& ParticleKernel::Local(int centre, double radius_m, const std::function<bool(int)>& eligible) {
  builder_.Build(graph_, centre, radius_m, eligible, local_);
  return local_;
}

std::pair<int, Pose2> ParticleKernel::LoopTo(const LocationHypothesis& h) {
  const GraphEdge& e = graph_.edge(h.edge);
  builder_.Build(graph_, e.from, e.length_m + 1e-6, {}, local_);
  const int matched = h.alpha < 0.5 ? e.from : e.to;
  return {matched, HypothesisPose(local_, h)->Between(local_.PoseOf(matched))};
}

}  // namespace catgraph
