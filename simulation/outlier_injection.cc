#include "simulation/outlier_injection.h"

#include <numbers>
#include <random>
#include <stdexcept>
#include <utility>

namespace catgraph {

std::vector<ClosureId> InjectRandomOutliers(PoseGraph2& graph, int count, std::uint64_t seed) {
  std::vector<PoseId> poses;
  for (const auto& [id, v] : graph.vertices) poses.push_back(id);
  const int n = static_cast<int>(poses.size());
  if (n < 4) throw std::invalid_argument("InjectRandomOutliers: need at least 4 poses");
  InformationMatrix<Pose2> information = InformationMatrix<Pose2>::Identity();
  for (const auto& c : graph.constraints) {
    if (!c.IsBetweenConsecutivePoses()) {
      information = c.measurement.information;
      break;
    }
  }
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> pick(0, n - 2);
  std::normal_distribution<double> xy(0.0, 0.3), theta(0.0, 10.0 * std::numbers::pi / 180.0);
  std::vector<ClosureId> injected;
  for (int k = 0; k < count; ++k) {
    int a = pick(rng), b = pick(rng);
    while (a == b) b = pick(rng);
    if (a > b) std::swap(a, b);
    if (b == a + 1) b = a + 2;
    Constraint<Pose2> c;
    c.id = graph.NextClosureId();
    c.from = poses[a];
    c.to = poses[b];
    const double dx = xy(rng), dy = xy(rng), dt = theta(rng);
    c.measurement = {Pose2(dx, dy, dt), information};
    c.kind = ClosureKind::kInjected;
    graph.constraints.push_back(c);
    injected.push_back(c.id);
  }
  return injected;
}

}  // namespace catgraph
