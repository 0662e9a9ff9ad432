#include "simulation/manhattan_world.h"

#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace catgraph {
namespace {

void Require(bool condition, const char* field, double value) {
  if (!condition) {
    throw std::invalid_argument(std::string("ManhattanWorldOptions::") + field +
                                " is out of range: " + std::to_string(value));
  }
}

Eigen::Matrix3d Information(double sigma_m, double sigma_rad) {
  return Eigen::Vector3d(1.0 / (sigma_m * sigma_m), 1.0 / (sigma_m * sigma_m),
                         1.0 / (sigma_rad * sigma_rad))
      .asDiagonal();
}

// The true relative pose perturbed by zero-mean Gaussian noise in its own
// frame: measured = true * (dx, dy, dtheta).
Pose2 Perturb(const Pose2& exact, double sigma_m, double sigma_rad, std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  const double dx = sigma_m * n(rng), dy = sigma_m * n(rng), dt = sigma_rad * n(rng);
  return exact * Pose2(dx, dy, dt);
}

}  // namespace

void Validate(const ManhattanWorldOptions& o) {
  Require(o.num_poses >= 2 && o.num_poses <= kMaxManhattanPoses, "num_poses", o.num_poses);
  Require(o.grid_step_m > 0.0, "grid_step_m", o.grid_step_m);
  Require(o.grid_cells >= 2, "grid_cells", o.grid_cells);
  Require(o.turn_probability >= 0.0 && o.turn_probability <= 1.0, "turn_probability",
          o.turn_probability);
  Require(o.closure_probability >= 0.0 && o.closure_probability <= 1.0, "closure_probability",
          o.closure_probability);
  Require(o.min_closure_separation >= 2, "min_closure_separation", o.min_closure_separation);
  Require(o.odometry_sigma_m > 0.0, "odometry_sigma_m", o.odometry_sigma_m);
  Require(o.odometry_sigma_rad > 0.0, "odometry_sigma_rad", o.odometry_sigma_rad);
  Require(o.closure_sigma_m > 0.0, "closure_sigma_m", o.closure_sigma_m);
  Require(o.closure_sigma_rad > 0.0, "closure_sigma_rad", o.closure_sigma_rad);
  if (const double edges = ExpectedManhattanEdges(o); edges > kMaxManhattanEdges) {
    throw std::invalid_argument("ManhattanWorldOptions: " + std::to_string(o.num_poses) + " poses on a " +
                                std::to_string(o.grid_cells) + "-step square would make about " +
                                std::to_string(static_cast<long long>(edges)) + " edges, more than " +
                                std::to_string(static_cast<long long>(kMaxManhattanEdges)) +
                                ": widen the square (grid_cells) or lower closure_probability");
  }
}

double ExpectedManhattanEdges(const ManhattanWorldOptions& o) {
  const double n = o.num_poses;
  const double points = static_cast<double>(o.grid_cells) * o.grid_cells;
  return n + o.closure_probability * n * n / (2.0 * points);
}

SimulatedPoseGraph2 SimulateManhattanWorld(const ManhattanWorldOptions& options) {
  Validate(options);
  std::mt19937_64 rng(options.seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);

  // The walk on integer grid points; heading in quarter turns.
  std::vector<std::pair<int, int>> cells{{0, 0}};
  std::vector<int> headings{0};
  constexpr int kDx[4] = {1, 0, -1, 0};
  constexpr int kDy[4] = {0, 1, 0, -1};
  const int limit = options.grid_cells / 2;
  auto inside = [limit](int x, int y) { return std::abs(x) <= limit && std::abs(y) <= limit; };
  for (int k = 1; k < options.num_poses; ++k) {
    auto [x, y] = cells.back();
    int heading = headings.back();
    if (uniform(rng) < options.turn_probability) heading = (heading + (uniform(rng) < 0.5 ? 1 : 3)) % 4;
    // Turn away from the boundary; one of the four directions is always free.
    for (int tries = 0; !inside(x + kDx[heading], y + kDy[heading]) && tries < 4; ++tries) {
      heading = (heading + (uniform(rng) < 0.5 ? 1 : 3)) % 4;
    }
    while (!inside(x + kDx[heading], y + kDy[heading])) heading = (heading + 1) % 4;
    cells.emplace_back(x + kDx[heading], y + kDy[heading]);
    headings.push_back(heading);
  }

  SimulatedPoseGraph2 out;
  std::vector<Pose2> truth;
  for (std::size_t k = 0; k < cells.size(); ++k) {
    truth.emplace_back(cells[k].first * options.grid_step_m, cells[k].second * options.grid_step_m,
                       headings[k] * std::numbers::pi / 2.0);
  }
  const Eigen::Matrix3d odometry_information =
      Information(options.odometry_sigma_m, options.odometry_sigma_rad);
  const Eigen::Matrix3d closure_information =
      Information(options.closure_sigma_m, options.closure_sigma_rad);

  auto add_edge = [&](int from, int to, const Pose2& noisy, const Eigen::Matrix3d& information,
                      ClosureKind kind) {
    const ClosureId id(static_cast<std::int64_t>(out.graph.constraints.size()));
    Constraint<Pose2> c{id, PoseId(from), PoseId(to), {noisy, information}, kind, {}, {}, {}, {}};
    out.graph.constraints.push_back(c);
    c.measurement.mean = truth[from].Between(truth[to]);
    out.truth.constraints.push_back(c);
  };

  std::map<std::pair<int, int>, std::vector<int>> visits;
  Pose2 chained = truth.front();
  for (int k = 0; k < options.num_poses; ++k) {
    if (k > 0) {
      const Pose2 odometry = Perturb(truth[k - 1].Between(truth[k]), options.odometry_sigma_m,
                                     options.odometry_sigma_rad, rng);
      chained = chained * odometry;
      add_edge(k - 1, k, odometry, odometry_information, ClosureKind::kOdometry);
    }
    out.graph.vertices.emplace(PoseId(k), Vertex<Pose2>{PoseId(k), chained, k == 0});
    out.truth.vertices.emplace(PoseId(k), Vertex<Pose2>{PoseId(k), truth[k], k == 0});
    for (int earlier : visits[cells[k]]) {
      if (k - earlier < options.min_closure_separation) continue;
      if (uniform(rng) >= options.closure_probability) continue;
      const Pose2 closure = Perturb(truth[k].Between(truth[earlier]), options.closure_sigma_m,
                                    options.closure_sigma_rad, rng);
      add_edge(k, earlier, closure, closure_information, ClosureKind::kUnknown);
    }
    visits[cells[k]].push_back(k);
  }
  return out;
}

}  // namespace catgraph
