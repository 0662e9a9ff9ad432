// Robust optimisation of Vertigo's Manhattan (g2o version) with 0, 100 and
// 1000 random false closures, per method.
//   build/bench/catgraph_bench_optimize --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
#include <filesystem>

#include <benchmark/benchmark.h>

#include "backend/io/graph_io.h"
#include "backend/pose_graph_optimizer.h"
#include "simulation/outlier_injection.h"

namespace catgraph {
namespace {

void BM_OptimizeManhattan(benchmark::State& state, RobustMethod method) {
  const auto path = std::filesystem::path(CATGRAPH_SHARED_DATASETS) /
                    "pose-graphs/vertigo/manhattan/originalDataset/g2o/manhattanOlson3500.g2o";
  if (!std::filesystem::exists(path)) {
    state.SkipWithError("shared dataset not found");
    return;
  }
  PoseGraph2 graph = std::get<PoseGraph2>(ReadGraphFile(path).graph);
  OutlierOptions outliers;
  outliers.count = static_cast<int>(state.range(0));
  InjectOutliers(graph, outliers);
  PoseGraphOptimizerOptions options;
  options.method = method;
  PoseGraphOptimization result;
  for (auto _ : state) {
    result = OptimizePoseGraph(graph, options);
  }
  state.counters["iterations"] = result.summary.iterations;
  state.counters["rejected"] = static_cast<double>(result.rejected);
  state.counters["usable"] = result.summary.IsUsable();
  state.counters["refine_s"] = result.refinement ? result.refinement->time_s : 0.0;
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

}  // namespace
}  // namespace catgraph

BENCHMARK_MAIN();
