// Streams a dataset through the online Mapper at its own pace and reports
// the latency of each stage per frame: reading and describing the image
// (features), the filters (CAT-Graph and CAT-Graph+), and the back end's
// re-solve after a frame that made closures; then the final solve and how
// the online map compares with the offline one.
//
//   catgraph simulate --scenario office-change -o office-change
//   OMP_NUM_THREADS=1 taskset -c 0 build/bench/catgraph_bench_mapper office-change [OPTIONS.yaml]
//
// OPTIONS.yaml: MapperOptions changed from the defaults (docs/file-formats.md
// "Options files"), e.g. `online: {max_iterations: 1}`.
//
// The vocabulary is trained before the stream (TrainMapVocabulary), as a
// robot would carry one; its time is reported apart.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <exception>
#include <map>
#include <string>
#include <vector>

#include "backend/evaluation.h"
#include "backend/io/image_file.h"
#include "backend/io/dataset.h"
#include "frontend/fabmap.h"
#include "frontend/localization.h"
#include "mapping/map_dataset.h"
#include "mapping/mapper.h"
#include "mapping/options_file.h"

namespace {

using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point since) { return std::chrono::duration<double>(Clock::now() - since).count(); }

// Mean, 95th percentile and maximum of `ms`, in milliseconds.
void PrintLatency(const char* stage, std::vector<double> ms) {
  if (ms.empty()) {
    std::printf("%-26s none\n", stage);
    return;
  }
  double sum = 0.0;
  for (const double v : ms) sum += v;
  std::sort(ms.begin(), ms.end());
  const double p95 = ms[std::min(ms.size() - 1, static_cast<std::size_t>(0.95 * static_cast<double>(ms.size())))];
  std::printf("%-26s n %5zu  mean %8.2f ms  p95 %8.2f ms  max %8.2f ms\n", stage, ms.size(),
              sum / static_cast<double>(ms.size()), p95, ms.back());
}

}  // namespace

int main(int argc, char** argv) {
  using namespace catgraph;
  if (argc != 2 && argc != 3) {
    std::fprintf(stderr, "usage: %s DATASET [OPTIONS.yaml]\n", argv[0]);
    return 2;
  }
  try {
    const Dataset d = ReadDataset(argv[1]);
    const auto training = Clock::now();
    const MapVocabulary vocabulary = TrainMapVocabulary(d, {});
    std::printf("vocabulary: %d words on %d frames in %.1f s\n", vocabulary.vocabulary.size(), vocabulary.frames,
                Seconds(training));
    const FabMapModel model(vocabulary.vocabulary.tree(), FabMapOptions{});
    mapping::MapperOptions options;
    if (argc == 3) mapping::ReadOptionsFile(argv[2], options);
    options.front_end.threads = 1;
    mapping::Mapper mapper(model, options);
    const std::vector<Pose2> odometry = PosesAtFrames(d, d.odometry), truth = PosesAtFrames(d, d.ground_truth);
    std::vector<double> features_ms, filter_ms, solve_ms, frame_ms;
    std::size_t closures = 0;
    const Trajectory2 truth_at_frames = mapping::TruthAtFrames(d);
    std::vector<double> online_ate_m;  // of the map so far, after each solve
    std::map<int, int> iterations;  // online solves by their iterations
    int rounds = 0;                 // solves, the hierarchy's re-solves included
    for (std::size_t k = 0; k < d.frames.size(); ++k) {
      const auto start = Clock::now();
      Observation z;
      z.words = vocabulary.vocabulary.Words(ReadImage(d.ImagePath(k)));
      const double features = 1e3 * Seconds(start);
      mapping::FrameResult r = mapper.AddFrame(
          {d.frames[k].timestamp_s, odometry[k], d.frames[k].traversal,
           truth.empty() ? std::nullopt : std::optional<Pose2>(truth[k])},
          z);
      const double total = 1e3 * Seconds(start);
      const double solve = r.solve ? 1e3 * r.solve->time_s : 0.0;
      features_ms.push_back(features);
      filter_ms.push_back(total - features - solve);
      if (r.solve) {
        solve_ms.push_back(solve);
        ++iterations[r.solve->iterations];
        rounds += r.solve->solves;
        if (!truth_at_frames.empty() && k > 0) {
          online_ate_m.push_back(EvaluateTrajectory(mapper.Map(), truth_at_frames).ate_m.rmse);
        }
      }
      frame_ms.push_back(total);
      closures += r.closures.size();
    }
    double sum = 0.0;
    for (const double v : frame_ms) sum += v;
    const double rate = 1e3 * static_cast<double>(frame_ms.size()) / sum;
    std::printf("%zu frames, %zu closures, %zu online solves; %.1f frames/s over the stream\n", d.frames.size(),
                closures, solve_ms.size(), rate);
    PrintLatency("features", features_ms);
    PrintLatency("filters", filter_ms);
    PrintLatency("online solve (closures)", solve_ms);
    PrintLatency("frame, all stages", frame_ms);
    std::printf("online solves by iterations:");
    for (const auto& [n, count] : iterations) std::printf("  %d: %d", n, count);
    std::printf("; %d solves with the hierarchy's\n", rounds);
    if (!online_ate_m.empty()) {
      double sum_ate = 0.0;
      for (const double a : online_ate_m) sum_ate += a;
      std::printf("online map's ATE after each solve (the frames so far): mean %.4f m, max %.4f m\n",
                  sum_ate / static_cast<double>(online_ate_m.size()),
                  *std::max_element(online_ate_m.begin(), online_ate_m.end()));
    }
    const auto final_start = Clock::now();
    const mapping::MapOutcome final_solve = mapper.Solve(truth_at_frames);
    std::printf("final solve (offline pipeline): %.2f s\n", Seconds(final_start));
    if (final_solve.ate_corrected) {
      std::printf("ATE: odometry %.4f m, online map %.4f m, final solve %.4f m\n",
                  final_solve.ate_odometry->ate_m.rmse,
                  EvaluateTrajectory(mapper.Map(), truth_at_frames).ate_m.rmse,
                  final_solve.ate_corrected->ate_m.rmse);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
