// False-positive sweeps: datasets x policies x outlier counts x seeds x
// methods, each run = inject, optimise, score. Runs go to a CSV as they finish
// (one appended line each, synced), so an interrupted sweep loses no finished
// run and a rerun with the same output resumes where it stopped. A sweep can
// be cut into deterministic shards for a cluster and the shards merged.
#ifndef CATGRAPH_EXPERIMENTS_SWEEP_H_
#define CATGRAPH_EXPERIMENTS_SWEEP_H_

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "backend/pose_graph_optimizer.h"
#include "simulation/outlier_injection.h"

namespace catgraph {

struct SweepDataset {
  std::string name;              // the key in the CSV; [A-Za-z0-9_.-]+
  std::filesystem::path graph;   // any pose-graph file
  std::filesystem::path truth;   // optional ground truth (trajectory_io.h formats)
};

struct SweepConfig {
  std::vector<SweepDataset> datasets;
  std::vector<RobustMethod> methods = {RobustMethod::kNone, RobustMethod::kSwitchable,
                                       RobustMethod::kDcs, RobustMethod::kCauchy,
                                       RobustMethod::kHuber, RobustMethod::kGnc};
  std::vector<OutlierPolicy> policies = {OutlierPolicy::kRandom, OutlierPolicy::kLocal,
                                         OutlierPolicy::kRandomGrouped,
                                         OutlierPolicy::kLocalGrouped};
  std::vector<int> outliers = {0, 10, 100, 500, 1000};
  std::vector<std::uint64_t> seeds = {1, 2, 3, 4, 5};
  int group_size = 0;     // 0: each policy's default
  int local_window = 20;
  PoseGraphOptimizerOptions optimizer;  // method is set per run
  std::filesystem::path output;         // CSV; may be set by the command line
};

// Reads a sweep configuration (JSON, or YAML for .yaml/.yml). Relative paths
// are relative to the configuration file. Throws FileError naming the file
// and the key at fault. docs/sweep.md documents every key.
SweepConfig ReadSweepConfigFile(const std::filesystem::path& path);

// One cell of the grid.
struct SweepRun {
  std::size_t index = 0;  // position in grid order
  std::string dataset;
  OutlierPolicy policy = OutlierPolicy::kRandom;
  int outliers = 0;
  std::uint64_t seed = 1;
  RobustMethod method = RobustMethod::kSwitchable;
  std::string Key() const;  // "dataset,policy,outliers,seed,method"
};

// Every run in grid order: dataset, policy, outliers, seed, method.
std::vector<SweepRun> SweepGrid(const SweepConfig& config);

struct Shard {
  int index = 0;  // 0 ... count-1
  int count = 1;
};
// "i/n" with 0 <= i < n; throws std::invalid_argument.
Shard ParseShard(const std::string& text);

struct SweepProgress {
  std::size_t done = 0;     // finished in this invocation
  std::size_t total = 0;    // to run in this invocation
  std::size_t resumed = 0;  // already in the CSV
  double elapsed_s = 0.0;
};

struct SweepOptions {
  Shard shard;
  int jobs = 0;  // worker threads; 0 = every core
  // Called (from worker threads, serialised) after each finished run.
  std::function<void(const SweepProgress&)> on_progress;
  // Set to stop: running runs finish and are written, no new run starts.
  const std::atomic<bool>* stop = nullptr;
};

struct SweepSummary {
  std::size_t planned = 0;   // runs in this shard
  std::size_t resumed = 0;   // found finished in the CSV
  std::size_t finished = 0;  // run now
  std::size_t failed = 0;    // of those, solver failures (recorded as such)
  bool stopped = false;      // interrupted through SweepOptions::stop
};

// Runs every run of the shard that the CSV at config.output does not hold
// yet and appends it there. A line cut off by a crash is removed first.
// Throws FileError for unreadable inputs or a CSV from another layout.
SweepSummary RunSweep(const SweepConfig& config, const SweepOptions& options = {});

// The CSV columns, in order.
const std::vector<std::string>& SweepColumns();

// A finished run read back: column name -> text.
using SweepRow = std::map<std::string, std::string>;
std::vector<SweepRow> ReadSweepCsv(const std::filesystem::path& path);

// Union of shard CSVs, one row per run key (the first seen), sorted by key;
// written atomically.
void MergeSweepCsv(const std::vector<std::filesystem::path>& inputs,
                   const std::filesystem::path& output);

// For each dataset in `csv`: "<prefix>-<dataset>.png" and ".svg" (ATE,
// precision and recall against outlier count, one panel per policy, one line
// per method, means over seeds) and "<prefix>-<dataset>.md" (the same as
// tables, with the success rate: ATE within 1.5x the outlier-free optimum).
// Returns the files written.
std::vector<std::filesystem::path> PlotSweep(const std::filesystem::path& csv,
                                             const std::string& prefix);

}  // namespace catgraph

#endif  // CATGRAPH_EXPERIMENTS_SWEEP_H_
