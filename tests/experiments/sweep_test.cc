// Sweeps: the grid, shards, configuration files, and the promise that an
// interrupted sweep loses no finished run and repeats none.
#include <fstream>
#include <set>

#include "tests/catch.h"

#include "experiments/sweep.h"
#include "backend/io/file_error.h"
#include "backend/io/graph_io.h"
#include "simulation/manhattan_world.h"
#include "tests/test_support.h"

namespace catgraph {
namespace {

// A small simulated dataset with ground truth and a config over it.
SweepConfig SmallSweep(const std::filesystem::path& dir) {
  ManhattanWorldOptions world;
  world.num_poses = 120;
  world.seed = 6;
  const SimulatedPoseGraph2 sim = SimulateManhattanWorld(world);
  WriteG2oFile(sim.graph, dir / "graph.g2o");
  WriteG2oFile(sim.truth, dir / "truth.g2o");
  SweepConfig c;
  c.datasets = {{"sim", dir / "graph.g2o", dir / "truth.g2o"}};
  c.methods = {RobustMethod::kNone, RobustMethod::kSwitchable};
  c.policies = {OutlierPolicy::kRandom, OutlierPolicy::kLocalGrouped};
  c.outliers = {0, 5};
  c.seeds = {1, 2, 3};
  c.output = dir / "runs.csv";
  return c;
}

std::map<std::string, SweepRow> RowsByKey(const std::filesystem::path& csv) {
  std::map<std::string, SweepRow> rows;
  for (SweepRow& r : ReadSweepCsv(csv)) {
    const std::string key = r.at("dataset") + "," + r.at("policy") + "," + r.at("outliers") +
                            "," + r.at("seed") + "," + r.at("method");
    CHECK(rows.emplace(key, std::move(r)).second);  // no run twice
  }
  return rows;
}

TEST_CASE("the grid is the full product in a fixed order and shards partition it",
          "[experiments][sweep]") {
  SweepConfig c;
  c.datasets = {{"a", "a.g2o", ""}, {"b", "b.g2o", ""}};
  const std::vector<SweepRun> grid = SweepGrid(c);
  CHECK(grid.size() == 2 * 4 * 5 * 5 * 6);
  CHECK(grid.front().Key() == "a,random,0,1,none");
  CHECK(grid[1].Key() == "a,random,0,1,switchable");
  CHECK(grid.back().Key() == "b,local-grouped,1000,5,gnc");
  std::set<std::string> keys;
  for (const SweepRun& r : grid) keys.insert(r.Key());
  CHECK(keys.size() == grid.size());

  CHECK(ParseShard("2/5").index == 2);
  CHECK(ParseShard("2/5").count == 5);
  CHECK_THROWS_WITH(ParseShard("5/5"), Catch::Contains("0 <= i < n"));
  CHECK_THROWS(ParseShard("1-3"));
  CHECK_THROWS(ParseShard("1/3x"));
}

TEST_CASE("YAML and JSON configurations read alike, unknown keys are errors",
          "[experiments][sweep][bad-input]") {
  const auto dir = testing::TempDir("sweep_config");
  std::ofstream(dir / "c.yaml") << "output: out.csv\ndatasets:\n  - name: m\n    graph: g.g2o\n"
                                   "    truth: /abs/t.dat\nmethods: [switchable, dcs]\n"
                                   "policies: [local]\noutliers: [0, 10]\nseeds: 3\n";
  std::ofstream(dir / "c.json") << R"({"output": "out.csv", "datasets": [{"name": "m",
      "graph": "g.g2o", "truth": "/abs/t.dat"}], "methods": ["switchable", "dcs"],
      "policies": ["local"], "outliers": [0, 10], "seeds": [1, 2, 3]})";
  for (const char* name : {"c.yaml", "c.json"}) {
    const SweepConfig c = ReadSweepConfigFile(dir / name);
    CAPTURE(name);
    CHECK(c.output == dir / "out.csv");
    CHECK(c.datasets.at(0).graph == dir / "g.g2o");
    CHECK(c.datasets.at(0).truth == "/abs/t.dat");
    CHECK(c.methods == std::vector<RobustMethod>{RobustMethod::kSwitchable, RobustMethod::kDcs});
    CHECK(c.seeds == std::vector<std::uint64_t>{1, 2, 3});
    CHECK(SweepGrid(c).size() == 12);
  }
  std::ofstream(dir / "bad.yaml") << "datasets: []\nmethod: [dcs]\n";
  CHECK_THROWS_WITH(ReadSweepConfigFile(dir / "bad.yaml"), Catch::Contains("unknown key 'method'"));
  std::ofstream(dir / "bad2.yaml") << "datasets:\n  - name: m\n    graph: g\nmethods: [magic]\n";
  CHECK_THROWS_WITH(ReadSweepConfigFile(dir / "bad2.yaml"), Catch::Contains("unknown method 'magic'"));
  std::ofstream(dir / "twice.yaml") << "datasets:\n  - {name: m, graph: a.g2o}\n  - {name: m, graph: b.g2o}\n";
  CHECK_THROWS_WITH(ReadSweepConfigFile(dir / "twice.yaml"), Catch::Contains("'m' is used twice"));
  std::ofstream(dir / "bad3.yaml") << "datasets: [\n";
  CHECK_THROWS_AS(ReadSweepConfigFile(dir / "bad3.yaml"), FileError);
  std::filesystem::remove_all(dir);
}

TEST_CASE("a sweep writes every run once with its scores", "[experiments][sweep]") {
  const auto dir = testing::TempDir("sweep_full");
  const SweepConfig c = SmallSweep(dir);
  SweepOptions options;
  options.jobs = 2;
  const SweepSummary s = RunSweep(c, options);
  CHECK(s.planned == 24);
  CHECK(s.finished == 24);
  CHECK(s.resumed == 0);
  CHECK(!s.stopped);
  const auto rows = RowsByKey(c.output);
  REQUIRE(rows.size() == 24);
  for (const auto& [key, r] : rows) {
    CAPTURE(key);
    CHECK(r.at("status") == "ok");
    CHECK(!r.at("ate_rmse").empty());
    const int outliers = std::stoi(r.at("outliers"));
    CHECK(std::stoi(r.at("false_positives")) + std::stoi(r.at("true_negatives")) == outliers);
  }
  // Switchable constraints reject the 5 false closures the plain solve keeps.
  CHECK(rows.at("sim,random,5,1,switchable").at("false_positives") == "0");
  CHECK(rows.at("sim,random,5,1,none").at("false_positives") == "5");
  // A finished sweep reruns nothing.
  const SweepSummary again = RunSweep(c, options);
  CHECK(again.finished == 0);
  CHECK(again.resumed == 24);
  // Plots and tables from the CSV.
  const auto files = PlotSweep(c.output, (dir / "plot").string());
  REQUIRE(files.size() == 3);
  CHECK(testing::ReadText(dir / "plot-sim.png").substr(1, 3) == "PNG");
  CHECK(testing::ReadText(dir / "plot-sim.svg").find("<svg") != std::string::npos);
  const std::string table = testing::ReadText(dir / "plot-sim.md");
  CHECK(table.find("| 5 | switchable | 3 |") != std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST_CASE("an interrupted sweep, rerun, loses no finished run and repeats none",
          "[experiments][sweep]") {
  const auto dir = testing::TempDir("sweep_resume");
  const SweepConfig c = SmallSweep(dir);
  std::atomic<bool> stop{false};
  SweepOptions options;
  options.jobs = 2;
  options.stop = &stop;
  options.on_progress = [&stop](const SweepProgress& p) {
    if (p.done >= 7) stop.store(true);
  };
  const SweepSummary first = RunSweep(c, options);
  CHECK(first.stopped);
  CHECK(first.finished >= 7);
  CHECK(first.finished < 24);
  const auto before = RowsByKey(c.output);
  CHECK(before.size() == first.finished);

  // A crash in the middle of writing leaves a cut line; the rerun removes it.
  std::ofstream(c.output, std::ios::app) << "sim,random,5,3,no";

  SweepOptions rerun;
  rerun.jobs = 2;
  const SweepSummary second = RunSweep(c, rerun);
  CHECK(second.resumed == first.finished);
  CHECK(second.finished == 24 - first.finished);
  const auto after = RowsByKey(c.output);
  CHECK(after.size() == 24);
  // The runs finished before the interruption are kept as they were (their
  // solve times would differ had they run again).
  for (const auto& [key, row] : before) CHECK(after.at(key) == row);
  std::filesystem::remove_all(dir);
}

TEST_CASE("shards run disjoint slices whose merge is the whole sweep", "[experiments][sweep]") {
  const auto dir = testing::TempDir("sweep_shards");
  SweepConfig c = SmallSweep(dir);
  std::vector<std::filesystem::path> parts;
  std::size_t total = 0;
  for (int i = 0; i < 3; ++i) {
    c.output = dir / ("shard" + std::to_string(i) + ".csv");
    SweepOptions options;
    options.shard = {i, 3};
    options.jobs = 1;
    total += RunSweep(c, options).finished;
    parts.push_back(c.output);
  }
  CHECK(total == 24);
  MergeSweepCsv(parts, dir / "merged.csv");
  const auto merged = RowsByKey(dir / "merged.csv");
  CHECK(merged.size() == 24);
  // Merging is idempotent: a shard given twice adds nothing.
  parts.push_back(parts.front());
  MergeSweepCsv(parts, dir / "merged2.csv");
  CHECK(RowsByKey(dir / "merged2.csv").size() == 24);
  // Another layout is refused with the file and line.
  std::ofstream(dir / "foreign.csv") << "a,b,c\n1,2,3\n";
  CHECK_THROWS_WITH(MergeSweepCsv({dir / "foreign.csv"}, dir / "m3.csv"),
                    Catch::Contains("foreign.csv:1: expected the sweep CSV header"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace catgraph
