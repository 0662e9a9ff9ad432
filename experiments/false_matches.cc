#include "experiments/false_matches.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>

namespace catgraph {
namespace {

// The frames, their odometry and truth, and what the filter will see of
// them: path length and time.
struct Track {
  std::vector<Pose2> odometry, truth;
  std::vector<double> path_m, time_s;
};

}  // namespace

std::vector<FalseVisualMatch> PlanFalseVisualMatches(const Dataset& d, const CatGraphOptions& filter,
                                                     const FalseMatchOptions& o) {
  auto fail = [](const std::string& what) { throw std::invalid_argument("false visual matches: " + what); };
  auto metres = [](double m) {
    std::ostringstream out;
    out << m << " m";
    return out.str();
  };
  if (o.count < 0) fail("the count must be >= 0");
  if (!(o.stretch_m > 0.0 && o.min_error_m > 0.0 && o.shape_tolerance_m > 0.0 && o.shape_tolerance_rad > 0.0 &&
        o.separation_m >= 0.0 && o.max_error_m >= o.min_error_m)) {
    fail("stretch, minimum error and shape tolerances must be > 0 and the separation >= 0");
  }
  if (o.count == 0) return {};
  if (d.ground_truth.empty()) fail("the dataset has no ground truth, so a match cannot be known to be false");
  if (d.odometry.empty()) fail("the dataset has no odometry");
  Track t;
  t.odometry = PosesAtFrames(d, d.odometry);
  t.truth = PosesAtFrames(d, d.ground_truth);
  const std::size_t n = d.frames.size();
  t.path_m.assign(n, 0.0);
  t.time_s.assign(n, 0.0);
  for (std::size_t k = 0; k < n; ++k) {
    t.time_s[k] = d.frames[k].timestamp_s;
    if (k > 0) t.path_m[k] = t.path_m[k - 1] + t.odometry[k - 1].Between(t.odometry[k]).translation().norm();
  }
  // Frames a and b (a < b) are one run of the filter: no sequence break between.
  std::vector<std::size_t> run(n, 0);
  for (std::size_t k = 1; k < n; ++k) {
    run[k] = run[k - 1] + (t.time_s[k] - t.time_s[k - 1] > filter.sequence_break_s ? 1 : 0);
  }
  auto older = [&](std::size_t old, std::size_t now) {  // outside the exclusion windows
    return t.time_s[now] - t.time_s[old] >= filter.exclusion_window_s &&
           t.path_m[now] - t.path_m[old] >= filter.exclusion_window_m;
  };

  // The last frame of the old stretch from j that frames k..end are taken
  // for, if it qualifies.
  auto old_stretch = [&](std::size_t k, std::size_t end, std::size_t j) -> std::optional<std::size_t> {
    std::size_t c = j;
    for (std::size_t i = k; i <= end; ++i) {
      while (c + 1 < n && t.path_m[c] - t.path_m[j] < t.path_m[i] - t.path_m[k]) ++c;
      // The filters stand on the edge from c to c + 1: both in one run, old enough.
      if (c + 1 >= n || run[c + 1] != run[j] || !older(c + 1, i)) return std::nullopt;
      const Pose2 now = t.odometry[k].Between(t.odometry[i]), then = t.odometry[j].Between(t.odometry[c]);
      if ((now.translation() - then.translation()).norm() > o.shape_tolerance_m ||
          std::abs(WrapAngle(now.theta() - then.theta())) > o.shape_tolerance_rad) {
        return std::nullopt;
      }
      const double error = (t.truth[i].translation() - t.truth[c].translation()).norm();
      if (error < o.min_error_m || error > o.max_error_m) return std::nullopt;
      const double gate = OdometricGateRadius(filter, t.path_m[i] - t.path_m[c]) - filter.hypothesis_radius_m;
      if ((t.odometry[i].translation() - t.odometry[c].translation()).norm() > gate) return std::nullopt;
    }
    return c;
  };

  std::mt19937_64 rng(o.seed ^ 0xA5A5F00DULL);
  std::vector<std::size_t> starts(n);
  std::iota(starts.begin(), starts.end(), std::size_t{0});
  std::shuffle(starts.begin(), starts.end(), rng);
  std::vector<FalseVisualMatch> plan;
  std::vector<std::pair<std::size_t, std::size_t>> qualifying;  // (j, old end)
  for (const std::size_t k : starts) {
    if (static_cast<int>(plan.size()) == o.count) break;
    std::size_t end = k;
    while (end + 1 < n && run[end + 1] == run[k] && t.path_m[end] - t.path_m[k] < o.stretch_m) ++end;
    if (t.path_m[end] - t.path_m[k] < o.stretch_m) continue;
    const bool apart = std::all_of(plan.begin(), plan.end(), [&](const FalseVisualMatch& m) {
      return t.path_m[k] - t.path_m[static_cast<std::size_t>(m.last_frame)] >= o.separation_m ||
             t.path_m[static_cast<std::size_t>(m.first_frame)] - t.path_m[end] >= o.separation_m;
    });
    if (!apart) continue;
    qualifying.clear();
    for (std::size_t j = 0; j < k && older(j, k); ++j) {
      if (const auto c = old_stretch(k, end, j)) qualifying.emplace_back(j, *c);
    }
    if (qualifying.empty()) continue;
    const auto [j, c] = qualifying[std::uniform_int_distribution<std::size_t>(0, qualifying.size() - 1)(rng)];
    plan.push_back({static_cast<int>(k), static_cast<int>(end), static_cast<int>(j), static_cast<int>(c)});
  }
  if (static_cast<int>(plan.size()) < o.count) {
    fail("only " + std::to_string(plan.size()) + " of the " + std::to_string(o.count) +
         " asked for fit this dataset (" + metres(o.stretch_m) + " stretches, " +
         metres(o.separation_m) + " apart, at least " + metres(o.min_error_m) +
         " from the truth, of the same shape as an old stretch inside the odometric gate)");
  }
  std::sort(plan.begin(), plan.end(),
            [](const FalseVisualMatch& a, const FalseVisualMatch& b) { return a.first_frame < b.first_frame; });
  return plan;
}

std::map<int, ClosureOverride> ImposedDecisions(const std::vector<FalseVisualMatch>& plan) {
  std::map<int, ClosureOverride> imposed;
  for (const FalseVisualMatch& m : plan) {
    if (!(m.matched_first_frame >= 0 && m.matched_last_frame >= 0 && m.first_frame < m.last_frame &&
          m.matched_first_frame < m.first_frame && m.matched_last_frame < m.first_frame)) {
      throw std::invalid_argument("a false visual match must map frames first < last onto older frames, not " +
                                  std::to_string(m.first_frame) + "-" + std::to_string(m.last_frame) + " onto " +
                                  std::to_string(m.matched_first_frame) + "-" + std::to_string(m.matched_last_frame));
    }
    for (int f = m.first_frame; f <= m.last_frame; ++f) {
      if (!imposed.try_emplace(f, ClosureOverride{.withhold = true}).second) {
        throw std::invalid_argument("false visual matches overlap at frame " + std::to_string(f));
      }
    }
    imposed[m.first_frame].force_node = m.matched_first_frame;
    imposed[m.last_frame].force_node = m.matched_last_frame;
  }
  return imposed;
}

}  // namespace catgraph
