// The front end: feature extraction and quantisation per frame, one
// CAT-Graph step at n_p = 1000 while revisiting (traversal 2 of office-change,
// the map of traversal 1 behind it), how that step grows when the map holds
// more nodes far from the robot, and the memory a graph node holds.
//   build/bench/catgraph_bench_frontend --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//
// The fixture simulates office-change and office-training into a temporary
// directory and extracts every frame's words once (about a minute).
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <memory>
#include <vector>

#include <benchmark/benchmark.h>
#include <opencv2/imgcodecs.hpp>

#include "backend/io/dataset.h"
#include "frontend/cat_graph.h"
#include "frontend/localization.h"
#include "frontend/vocabulary.h"
#include "simulation/office_simulator.h"
#include "simulation/scenario.h"

namespace catgraph {
namespace {

struct Fixture {
  Dataset change, training;
  std::unique_ptr<Vocabulary> vocabulary;
  std::unique_ptr<FabMapModel> model;
  std::vector<WordSet> change_words, training_words;
  std::vector<Pose2> change_u, training_u;  // odometry since the previous frame

  Fixture() {
    const auto dir = std::filesystem::temp_directory_path() / "catgraph_bench_frontend";
    SimulateDataset(LoadScenario("office-change"), dir / "office-change", {});
    SimulateDataset(LoadScenario("office-training"), dir / "office-training", {});
    change = ReadDataset(dir / "office-change");
    training = ReadDataset(dir / "office-training");
    // The localize command's default: 500 words from about 200 frames of
    // traversal 1.
    std::vector<cv::Mat> images;
    for (std::size_t i = 0; i < change.frames.size(); i += 8) {
      if (change.frames[i].traversal == 1) images.push_back(ReadImage(change.ImagePath(i)));
    }
    VocabularyOptions options;
    options.words = 500;
    vocabulary = std::make_unique<Vocabulary>(TrainVocabulary(images, options));
    model = std::make_unique<FabMapModel>(vocabulary->tree(), FabMapOptions{});
    change_words = ExtractWords(change, *vocabulary, {});
    training_words = ExtractWords(training, *vocabulary, {});
    change_u = Increments(change);
    training_u = Increments(training);
  }

  static std::vector<Pose2> Increments(const Dataset& d) {
    std::vector<Pose2> u(d.frames.size());
    for (std::size_t k = 1; k < d.frames.size(); ++k) {
      u[k] = InterpolatePose(d.odometry, d.frames[k - 1].timestamp_s)
                 .Between(InterpolatePose(d.odometry, d.frames[k].timestamp_s));
    }
    return u;
  }
};

const Fixture& SharedFixture() {
  static const Fixture fixture;
  return fixture;
}

// SIFT on one 261 x 101 frame and its quantisation to the 500 words.
void BM_FeaturesAndWords(benchmark::State& state) {
  const Fixture& f = SharedFixture();
  std::size_t i = 0;
  std::vector<cv::Mat> images;
  for (std::size_t k = 0; k < f.change.frames.size(); k += 61) images.push_back(ReadImage(f.change.ImagePath(k)));
  for (auto _ : state) {
    benchmark::DoNotOptimize(f.vocabulary->Words(images[i]));
    i = (i + 1) % images.size();
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_FeaturesAndWords)->Unit(benchmark::kMillisecond);

// A filter that has seen `extra_laps` laps of office-training far away (a
// sequence break and 1 km of odometry between them and office-change) and
// then traversal 1 of office-change: its map is traversal 1 plus
// 3187 x extra_laps nodes outside every local graph.
int FeedMap(const Fixture& f, CatGraphFilter& filter, int extra_laps, double& time_s) {
  int frame = 0;
  for (int lap = 0; lap < extra_laps; ++lap) {
    for (std::size_t k = 0; k < f.training.frames.size(); ++k, ++frame) {
      time_s += k == 0 ? 100.0 : f.training.frames[k].timestamp_s - f.training.frames[k - 1].timestamp_s;
      filter.Step(frame, time_s, k == 0 ? Pose2(1000.0, 0.0, 0.0) : f.training_u[k], f.training_words[k]);
    }
  }
  std::size_t k = 0;
  for (; f.change.frames[k].traversal == 1; ++k, ++frame) {
    time_s += k == 0 ? (extra_laps > 0 ? 100.0 : 0.0) : f.change.frames[k].timestamp_s - f.change.frames[k - 1].timestamp_s;
    filter.Step(frame, time_s, k == 0 ? Pose2(-1000.0 * extra_laps, 0.0, 0.0) : f.change_u[k], f.change_words[k]);
  }
  return frame;
}

// One CAT-Graph step (motion, Eq 1-2, new place, Eq 4, graph update,
// resampling), with or without CAT-Graph+'s odometric filter and
// validation, on traversal 2 of office-change, feature extraction excluded.
// Counters: per-step percentiles over the timed steps (ms), the share of
// steps that closed a loop, and the heap bytes per graph node.
void BM_FilterStep(benchmark::State& state) {
  const Fixture& f = SharedFixture();
  const int extra_laps = static_cast<int>(state.range(0));
  CatGraphOptions options;  // n_p = 1000, Table I
  const int odometric_copies = static_cast<int>(state.range(1));
  options.inference.enabled = odometric_copies > 0;  // CAT-Graph+ beside it
  if (odometric_copies == 1) options.inference.seed_local = false;  // O as the spec's copy of V
  if (odometric_copies > 0) options.inference.particle_factor = odometric_copies;
  std::unique_ptr<CatGraphFilter> filter;
  std::size_t k = f.change.frames.size();
  int frame = 0;
  double time_s = 0.0;
  std::vector<double> step_ms;
  int closures = 0;
  for (auto _ : state) {
    if (k == f.change.frames.size()) {  // a fresh map, outside the timing
      state.PauseTiming();
      filter = std::make_unique<CatGraphFilter>(*f.model, options);
      time_s = 0.0;
      frame = FeedMap(f, *filter, extra_laps, time_s);
      k = static_cast<std::size_t>(std::count_if(f.change.frames.begin(), f.change.frames.end(),
                                                 [](const DatasetFrame& x) { return x.traversal == 1; }));
      state.ResumeTiming();
    }
    time_s += f.change.frames[k].timestamp_s - f.change.frames[k - 1].timestamp_s;
    const auto t0 = std::chrono::steady_clock::now();
    const CatGraphStep step = filter->Step(frame++, time_s, f.change_u[k], f.change_words[k]);
    step_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    closures += step.closure ? 1 : 0;
    ++k;
  }
  std::sort(step_ms.begin(), step_ms.end());
  auto at = [&](double q) { return step_ms[static_cast<std::size_t>(q * static_cast<double>(step_ms.size() - 1))]; };
  state.counters["p50_ms"] = at(0.5);
  state.counters["p95_ms"] = at(0.95);
  state.counters["max_ms"] = step_ms.back();
  state.counters["closed"] = static_cast<double>(closures) / static_cast<double>(step_ms.size());
  state.counters["nodes"] = static_cast<double>(filter->graph().nodes().size());
  double bytes = 0.0;
  for (const GraphNode& n : filter->graph().nodes()) {
    bytes += sizeof(GraphNode) + n.observation.words.capacity() * sizeof(int) + n.edges.capacity() * sizeof(int);
  }
  bytes += static_cast<double>(filter->graph().edges().capacity() * sizeof(GraphEdge));
  state.counters["bytes_per_node"] = bytes / static_cast<double>(filter->graph().nodes().size());
}
// Args: extra laps far away; CAT-Graph+'s odometric filter: 0 none (CAT-Graph
// alone), 1 the spec's copy of the visual particles, 5 the default (five
// copies of those near the match).
BENCHMARK(BM_FilterStep)
    ->Args({0, 0})
    ->Args({1, 0})
    ->Args({4, 0})
    ->Args({0, 1})
    ->Args({0, 5})
    ->Args({4, 5})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1460);

}  // namespace
}  // namespace catgraph

BENCHMARK_MAIN();
