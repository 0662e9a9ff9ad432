// Reading, summarising and writing pose graphs.
//   build/bench/catgraph_bench_io --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <filesystem>
#include <sstream>

#include <benchmark/benchmark.h>

#include "backend/graph_summary.h"
#include "backend/io/graph_io.h"
#include "simulation/manhattan_world.h"

namespace catgraph {
namespace {

const std::filesystem::path kShared = CATGRAPH_SHARED_DATASETS "/pose-graphs";

void BM_ReadSharedGraph(benchmark::State& state, const char* relative) {
  const auto path = kShared / relative;
  if (!std::filesystem::exists(path)) {
    state.SkipWithError("shared dataset not found");
    return;
  }
  for (auto _ : state) benchmark::DoNotOptimize(ReadGraphFile(path));
}
BENCHMARK_CAPTURE(BM_ReadSharedGraph, manhattan_g2o,
                  "vertigo/manhattan/originalDataset/g2o/manhattanOlson3500.g2o")
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ReadSharedGraph, ais2klinik, "se-sync/ais2klinik.g2o")
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ReadSharedGraph, cubicle_3d, "se-sync/cubicle.g2o")
    ->Unit(benchmark::kMillisecond);

void BM_WriteG2o(benchmark::State& state) {
  ManhattanWorldOptions options;
  options.num_poses = static_cast<int>(state.range(0));
  const AnyPoseGraph graph = SimulateManhattanWorld(options).graph;
  for (auto _ : state) {
    std::ostringstream out;
    WriteG2o(graph, out);
    benchmark::DoNotOptimize(out.str().size());
  }
}
BENCHMARK(BM_WriteG2o)->Arg(3500)->Unit(benchmark::kMillisecond);

void BM_Summarize(benchmark::State& state) {
  ManhattanWorldOptions options;
  options.num_poses = static_cast<int>(state.range(0));
  const AnyPoseGraph graph = SimulateManhattanWorld(options).graph;
  for (auto _ : state) benchmark::DoNotOptimize(Summarize(graph));
}
BENCHMARK(BM_Summarize)->Arg(3500)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace catgraph

BENCHMARK_MAIN();
