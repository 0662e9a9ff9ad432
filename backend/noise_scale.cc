#include "backend/noise_scale.h"

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <type_traits>
#include <utility>
#include <vector>

#include "backend/chi_square.h"
#include "backend/factor_graph.h"
#include "backend/factors.h"
#include "backend/optimizer.h"

namespace catgraph {

void Validate(const NoiseScaleOptions& o) {
  auto require = [](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(std::string("NoiseScaleOptions: ") + what);
  };
  require(o.window >= 1, "noise_scale.window must be >= 1");
  require(o.max_cycles >= 1, "noise_scale.max_cycles must be >= 1");
  require(o.min_cycles >= 1, "noise_scale.min_cycles must be >= 1");
  require(o.quantile > 0.0 && o.quantile < 1.0, "noise_scale.quantile must be in (0, 1)");
  require(o.upper_quantile > o.quantile && o.upper_quantile < 1.0,
          "noise_scale.upper_quantile must be in (quantile, 1)");
}

namespace {

template <typename PoseT>
class CycleFinder {
 public:
  CycleFinder(const PoseGraph<PoseT>& graph, int window, const std::set<ClosureId>& excluded)
      : window_(window) {
    for (const auto& c : graph.constraints) {
      if (c.kind == ClosureKind::kOdometry && c.IsBetweenConsecutivePoses()) {
        odometry_.emplace(std::min(c.from.value(), c.to.value()), &c);
      } else if (c.from != c.to && !excluded.contains(c.id)) {
        const std::int64_t lo = std::min(c.from.value(), c.to.value());
        const std::int64_t hi = std::max(c.from.value(), c.to.value());
        by_low_end_[lo].push_back({hi, &c});
        closures_.push_back({lo, hi, &c});
      }
    }
  }

  struct Cycle {
    const Constraint<PoseT>* first;
    const Constraint<PoseT>* second;
    std::int64_t a, a2, b_min, b_max;
  };

  std::size_t num_closures() const { return closures_.size(); }

  // The partner nearest to closure k, if there is one.
  std::optional<Cycle> CycleOf(std::size_t k) const {
    const auto [a, b, first] = closures_[k];
    std::optional<Cycle> best;
    std::int64_t best_distance = std::numeric_limits<std::int64_t>::max();
    for (std::int64_t step = 1; step <= window_; ++step) {
      const auto partners = by_low_end_.find(a + step);
      if (partners == by_low_end_.end()) continue;
      for (const auto& [b2, second] : partners->second) {
        const std::int64_t distance = step + std::abs(b2 - b);
        const std::int64_t b_min = std::min(b, b2), b_max = std::max(b, b2);
        if (std::abs(b2 - b) > window_ || distance >= best_distance || a + step >= b_min ||
            !Chained(a, a + step) || !Chained(b_min, b_max)) {
          continue;
        }
        best = Cycle{first, second, a, a + step, b_min, b_max};
        best_distance = distance;
      }
    }
    return best;
  }

  // The chi2 of the cycle's own least-squares solution, if it solved.
  std::optional<double> Chi2(const Cycle& cycle) const {
    Values initial;
    FactorGraph factors;
    // Poses chained from a at the identity: a..a2 by odometry, then b across
    // the first closure, then b_min..b_max by odometry both ways from b.
    std::map<std::int64_t, PoseT> poses;
    poses[cycle.a] = PoseT();
    for (std::int64_t p = cycle.a; p < cycle.a2; ++p) poses[p + 1] = poses[p] * Step(p, p + 1);
    const std::int64_t b = Other(*cycle.first, cycle.a);
    poses[b] = poses[cycle.a] * Relative(*cycle.first, cycle.a);
    for (std::int64_t p = b; p < cycle.b_max; ++p) poses[p + 1] = poses[p] * Step(p, p + 1);
    for (std::int64_t p = b; p > cycle.b_min; --p) poses[p - 1] = poses[p] * Step(p, p - 1);
    for (const auto& [id, pose] : poses) initial.Insert(PoseId(id), pose);
    auto add = [&factors](const Constraint<PoseT>& c) {
      factors.Emplace<BetweenFactor<PoseT>>(c.from, c.to, c.measurement);
    };
    for (std::int64_t p = cycle.a; p < cycle.a2; ++p) add(*odometry_.at(p));
    for (std::int64_t p = cycle.b_min; p < cycle.b_max; ++p) add(*odometry_.at(p));
    add(*cycle.first);
    add(*cycle.second);
    factors.SetConstant(PoseKey(PoseId(cycle.a)));
    OptimizerOptions options;
    options.max_iterations = 50;
    const OptimizationResult result = Optimize(factors, initial, options);
    if (!result.summary.IsUsable()) return std::nullopt;
    return 2.0 * result.summary.final_cost;  // Ceres' cost is half the chi2
  }

 private:
  bool Chained(std::int64_t from, std::int64_t to) const {
    for (std::int64_t p = from; p < to; ++p) {
      if (!odometry_.contains(p)) return false;
    }
    return true;
  }
  static std::int64_t Other(const Constraint<PoseT>& c, std::int64_t end) {
    return c.from.value() == end ? c.to.value() : c.from.value();
  }
  // The measured pose of the constraint's other end in the frame of `end`.
  static PoseT Relative(const Constraint<PoseT>& c, std::int64_t end) {
    return c.from.value() == end ? c.measurement.mean : c.measurement.mean.Inverse();
  }
  PoseT Step(std::int64_t from, std::int64_t to) const {
    return Relative(*odometry_.at(std::min(from, to)), from);
  }

  const std::int64_t window_;
  std::map<std::int64_t, const Constraint<PoseT>*> odometry_;  // lower id -> edge
  std::map<std::int64_t, std::vector<std::pair<std::int64_t, const Constraint<PoseT>*>>> by_low_end_;
  struct Closure {
    std::int64_t low, high;
    const Constraint<PoseT>* constraint;
  };
  std::vector<Closure> closures_;
};

template <typename PoseT>
NoiseScaleEstimate Estimate(const PoseGraph<PoseT>& graph, const NoiseScaleOptions& options,
                            const std::set<ClosureId>& excluded) {
  Validate(options);
  const CycleFinder<PoseT> finder(graph, options.window, excluded);
  std::vector<typename CycleFinder<PoseT>::Cycle> cycles;
  for (std::size_t k = 0; k < finder.num_closures(); ++k) {
    if (auto cycle = finder.CycleOf(k)) cycles.push_back(*cycle);
  }
  // At most max_cycles of them, spread evenly over the graph.
  const std::size_t n = std::min(cycles.size(), static_cast<std::size_t>(options.max_cycles));
  std::vector<double> chi2;
  for (std::size_t i = 0; i < n; ++i) {
    if (auto value = finder.Chi2(cycles[i * cycles.size() / n])) chi2.push_back(*value);
  }
  NoiseScaleEstimate estimate;
  estimate.cycles = static_cast<int>(chi2.size());
  if (estimate.cycles < options.min_cycles) return estimate;
  constexpr int kDof = std::is_same_v<PoseT, Pose2> ? 3 : 6;
  auto scale_at = [&chi2](double quantile) {
    const auto q = chi2.begin() + static_cast<std::ptrdiff_t>(quantile * (chi2.size() - 1));
    std::nth_element(chi2.begin(), q, chi2.end());
    return *q / ChiSquareQuantile(kDof, quantile);
  };
  estimate.scale = scale_at(options.quantile);
  estimate.upper_scale = scale_at(options.upper_quantile);
  return estimate;
}

}  // namespace

NoiseScaleEstimate EstimateNoiseScale(const PoseGraph2& graph, const NoiseScaleOptions& options,
                                      const std::set<ClosureId>& excluded) {
  return Estimate(graph, options, excluded);
}
NoiseScaleEstimate EstimateNoiseScale(const PoseGraph3& graph, const NoiseScaleOptions& options,
                                      const std::set<ClosureId>& excluded) {
  return Estimate(graph, options, excluded);
}

}  // namespace catgraph
