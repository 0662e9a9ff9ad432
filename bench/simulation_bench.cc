// The office simulator: rendering one camera frame, encoding it, building
// the world's textures, and a whole simulated dataset.
//   build/bench/catgraph_bench_simulation --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <filesystem>
#include <vector>

#include <benchmark/benchmark.h>
#include <opencv2/imgcodecs.hpp>

#include "simulation/office_simulator.h"
#include "simulation/scenario.h"

namespace catgraph {
namespace {

// Frames spread over the whole office-change run, both traversals.
struct Fixture {
  Scenario scenario = LoadScenario("office-change");
  OfficeWorld world = MakeWorld(scenario);
  std::vector<PlannedFrame> frames =
      PlanFrames(DriveScenario(scenario, 1), scenario.camera.frame_rate_hz, 0);
};

const Fixture& SharedFixture() {
  static const Fixture fixture;
  return fixture;
}

// One thread; the target is >= 200 frames/s on one core (BENCHMARKS.md).
void BM_RenderFrame(benchmark::State& state) {
  const Fixture& f = SharedFixture();
  std::size_t i = 0;
  for (auto _ : state) {
    const PlannedFrame& frame = f.frames[i];
    benchmark::DoNotOptimize(f.world.Render(frame.T_world_camera, frame.traversal, i));
    i = (i + 37) % f.frames.size();
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_RenderFrame)->Unit(benchmark::kMicrosecond);

void BM_RenderAndEncodePng(benchmark::State& state) {
  const Fixture& f = SharedFixture();
  std::size_t i = 0;
  std::vector<std::uint8_t> png;
  for (auto _ : state) {
    const PlannedFrame& frame = f.frames[i];
    cv::imencode(".png", f.world.Render(frame.T_world_camera, frame.traversal, i), png);
    benchmark::DoNotOptimize(png.data());
    i = (i + 37) % f.frames.size();
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_RenderAndEncodePng)->Unit(benchmark::kMicrosecond);

// Textures of every wall and piece of furniture, with their mip-maps.
void BM_BuildWorld(benchmark::State& state) {
  const Scenario scenario = LoadScenario("office-change");
  for (auto _ : state) benchmark::DoNotOptimize(MakeWorld(scenario));
}
BENCHMARK(BM_BuildWorld)->Unit(benchmark::kMillisecond);

// The whole office-change dataset (about 3050 frames) written to disk, with
// every core.
void BM_SimulateOfficeChange(benchmark::State& state) {
  const Scenario scenario = LoadScenario("office-change");
  const auto dir = std::filesystem::temp_directory_path() / "catgraph_bench_simulate";
  for (auto _ : state) {
    benchmark::DoNotOptimize(SimulateDataset(scenario, dir, {}));
  }
  std::filesystem::remove_all(dir);
}
BENCHMARK(BM_SimulateOfficeChange)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

}  // namespace
}  // namespace catgraph

BENCHMARK_MAIN();
