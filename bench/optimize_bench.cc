// Robust optimisation of Vertigo's Manhattan (g2o version) with 0, 100 and
// 1000 random false closures, per method; and of SE-Sync's 3D benchmarks,
// clean, plain and switchable. Counters say where the time goes. Then the
// joint marginals readmission tests closures by, and whole solves of a
// generated world of City10000's shape with each stage's seconds.
//   build/bench/catgraph_bench_optimize --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
//   build/bench/catgraph_bench_optimize --benchmark_filter=3D
//   build/bench/catgraph_bench_optimize --benchmark_filter=JointMarginals
//   build/bench/catgraph_bench_optimize --benchmark_filter=CityShaped
//   build/bench/catgraph_bench_optimize --benchmark_filter=FillReducingOrder
#include <filesystem>
#include <optional>
#include <random>
#include <utility>
#include <vector>

#include <benchmark/benchmark.h>

#include "backend/elimination_ordering.h"
#include "backend/factors.h"
#include "backend/io/graph_io.h"
#include "backend/optimizer.h"
#include "backend/pose_graph_optimizer.h"
#include "simulation/manhattan_world.h"
#include "simulation/outlier_injection.h"

namespace catgraph {
namespace {

// Iterations, decisions, and the seconds of each stage: the initial guess,
// then Ceres' breakdown of the robust solve and the refinement together, then
// the wall-clock seconds of every stage OptimizePoseGraph ran.
void SetCounters(benchmark::State& state, const PoseGraphOptimization& result) {
  state.counters["iterations"] = result.summary.iterations;
  state.counters["rejected"] = static_cast<double>(result.rejected);
  state.counters["usable"] = result.summary.IsUsable();
  state.counters["refine_s"] = result.refinement ? result.refinement->time_s : 0.0;
  const Summary solves = result.SolveTimes();
  state.counters["init_s"] = result.initial_guess_time_s;
  state.counters["linear_s"] = solves.linear_solver_time_s;
  state.counters["jacobian_s"] = solves.jacobian_time_s;
  state.counters["residual_s"] = solves.residual_time_s;
  state.counters["preprocess_s"] = solves.preprocessor_time_s;
  for (const StageTime& stage : result.stages) state.counters[stage.stage + "_stage_s"] = stage.time_s;
}

// Optimises `graph` once per benchmark iteration with the method's defaults.
void OptimizeEachIteration(benchmark::State& state, const AnyPoseGraph& graph, RobustMethod method) {
  PoseGraphOptimizerOptions options;
  options.method = method;
  PoseGraphOptimization result;
  for (auto _ : state) {
    result = OptimizePoseGraph(graph, options);
  }
  SetCounters(state, result);
}

// The shared graph, or nothing when the shared folder is absent.
std::optional<AnyPoseGraph> ReadShared(benchmark::State& state, const char* relative) {
  const auto path = std::filesystem::path(CATGRAPH_SHARED_DATASETS) / "pose-graphs" / relative;
  if (!std::filesystem::exists(path)) {
    state.SkipWithError("shared dataset not found");
    return std::nullopt;
  }
  return ReadGraphFile(path).graph;
}

void BM_OptimizeManhattan(benchmark::State& state, RobustMethod method) {
  std::optional<AnyPoseGraph> graph =
      ReadShared(state, "vertigo/manhattan/originalDataset/g2o/manhattanOlson3500.g2o");
  if (!graph) return;
  OutlierOptions outliers;
  outliers.count = static_cast<int>(state.range(0));
  InjectOutliers(*graph, outliers);
  OptimizeEachIteration(state, *graph, method);
}

#define CATGRAPH_OPTIMIZE_BENCH(name, method)                              \
  BENCHMARK_CAPTURE(BM_OptimizeManhattan, name, method)                   \
      ->Arg(0)->Arg(100)->Arg(1000)->Unit(benchmark::kMillisecond)->Iterations(1)

CATGRAPH_OPTIMIZE_BENCH(none, RobustMethod::kNone);
CATGRAPH_OPTIMIZE_BENCH(switchable, RobustMethod::kSwitchable);
CATGRAPH_OPTIMIZE_BENCH(dcs, RobustMethod::kDcs);
CATGRAPH_OPTIMIZE_BENCH(cauchy, RobustMethod::kCauchy);
CATGRAPH_OPTIMIZE_BENCH(huber, RobustMethod::kHuber);
CATGRAPH_OPTIMIZE_BENCH(gnc, RobustMethod::kGnc);

// A clean 3D graph from SE-Sync's benchmarks, with the default initial guess.
void BM_Optimize3D(benchmark::State& state, const char* file, RobustMethod method) {
  if (const std::optional<AnyPoseGraph> graph = ReadShared(state, file)) {
    OptimizeEachIteration(state, *graph, method);
  }
}

#define CATGRAPH_OPTIMIZE_3D_BENCH(name, file)                                               \
  BENCHMARK_CAPTURE(BM_Optimize3D, name##_none, file, RobustMethod::kNone)                  \
      ->Unit(benchmark::kMillisecond)->Iterations(1);                                        \
  BENCHMARK_CAPTURE(BM_Optimize3D, name##_switchable, file, RobustMethod::kSwitchable)      \
      ->Unit(benchmark::kMillisecond)->Iterations(1)

CATGRAPH_OPTIMIZE_3D_BENCH(smallGrid3D, "se-sync/smallGrid3D.g2o");
CATGRAPH_OPTIMIZE_3D_BENCH(sphere_bignoise, "se-sync/sphere_bignoise_vertex3.g2o");
CATGRAPH_OPTIMIZE_3D_BENCH(parking_garage, "se-sync/parking-garage.g2o");
CATGRAPH_OPTIMIZE_3D_BENCH(torus3D, "se-sync/torus3D.g2o");
CATGRAPH_OPTIMIZE_3D_BENCH(cubicle, "se-sync/cubicle.g2o");

// The joint marginal covariances of 1000 random pairs of poses of a
// generated Manhattan world of state.range(0) poses, at its true poses, its
// first pose held constant (as readmission tests 1000 rejected closures).
void BM_JointMarginals(benchmark::State& state) {
  ManhattanWorldOptions world;
  world.num_poses = static_cast<int>(state.range(0));
  const PoseGraph2 truth = SimulateManhattanWorld(world).truth;
  Values values;
  FactorGraph graph;
  for (const auto& [id, vertex] : truth.vertices) values.Insert(id, *vertex.pose);
  for (const auto& c : truth.constraints) graph.Emplace<BetweenFactor<Pose2>>(c.from, c.to, c.measurement);
  graph.SetConstant(PoseKey(truth.vertices.begin()->first));
  std::mt19937 rng(1);
  std::uniform_int_distribution<int> pose(0, world.num_poses - 1);
  std::vector<std::pair<Key, Key>> pairs;
  for (int k = 0; k < 1000; ++k) pairs.emplace_back(PoseKey(PoseId(pose(rng))), PoseKey(PoseId(pose(rng))));
  for (auto _ : state) {
    benchmark::DoNotOptimize(JointMarginalCovariances(graph, values, pairs));
  }
  state.counters["edges"] = static_cast<double>(truth.constraints.size());
}
BENCHMARK(BM_JointMarginals)->Arg(1000)->Arg(3000)->Arg(10000)->Unit(benchmark::kMillisecond)->Iterations(1);

// FillReducingOrder on a generated world of state.range(0) poses (a 50-step
// square) whose closures are all switchable, as every robust solve asks for
// it: at 3000 poses it keeps Ceres' own order (its time is then overhead of
// each solve), at 10,000 it orders by nested dissection.
void BM_FillReducingOrder(benchmark::State& state) {
  ManhattanWorldOptions world;
  world.num_poses = static_cast<int>(state.range(0));
  world.grid_cells = 50;
  const PoseGraph2 truth = SimulateManhattanWorld(world).truth;
  Values values;
  FactorGraph graph;
  for (const auto& [id, vertex] : truth.vertices) values.Insert(id, *vertex.pose);
  int switches = 0;
  for (const auto& c : truth.constraints) {
    if (c.IsBetweenConsecutivePoses()) {
      graph.Emplace<BetweenFactor<Pose2>>(c.from, c.to, c.measurement);
      continue;
    }
    const SwitchId s(switches++);
    values.Insert(s, 1.0);
    graph.Emplace<SwitchableBetweenFactor<Pose2>>(c.from, c.to, s, c.measurement);
    graph.Emplace<SwitchPriorFactor>(s, SwitchPrior{1.0, 1.0});
  }
  graph.SetConstant(PoseKey(truth.vertices.begin()->first));
  std::size_t ordered = 0;
  for (auto _ : state) ordered = FillReducingOrder(graph, values).size();
  state.counters["ordered"] = static_cast<double>(ordered);
  state.counters["factors"] = static_cast<double>(graph.size());
}
BENCHMARK(BM_FillReducingOrder)->Arg(3000)->Arg(10000)->Unit(benchmark::kMillisecond);

// A generated world of City10000's shape (10,000 poses on a 50-step square:
// 21,603 edges, City10000 has 20,687) with state.range(0) random false
// closures, solved with the defaults.
void BM_OptimizeCityShaped(benchmark::State& state) {
  ManhattanWorldOptions world;
  world.num_poses = 10'000;
  world.grid_cells = 50;
  AnyPoseGraph graph = SimulateManhattanWorld(world).graph;
  OutlierOptions outliers;
  outliers.count = static_cast<int>(state.range(0));
  InjectOutliers(graph, outliers);
  OptimizeEachIteration(state, graph, RobustMethod::kSwitchable);
}
BENCHMARK(BM_OptimizeCityShaped)->Arg(0)->Arg(100)->Arg(1000)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace
}  // namespace catgraph

BENCHMARK_MAIN();
