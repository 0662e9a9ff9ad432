// The experiment harness as library calls, on the short simulated office:
// the hierarchy experiment and the inference sweep, against what the
// libraries they call give directly.
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "tests/catch.h"

#include "backend/io/dataset.h"
#include "experiments/hierarchy_experiment.h"
#include "experiments/inference_sweep.h"
#include "frontend/fabmap.h"
#include "frontend/localization.h"
#include "simulation/office_simulator.h"
#include "simulation/scenario.h"
#include "tests/test_support.h"

namespace catgraph {
namespace {

TEST_CASE("the hierarchy experiment and the inference sweep as library calls on the short office",
          "[experiments][slow]") {
  const auto root = testing::TempDir("experiments");
  Scenario scenario = LoadScenario(testing::Fixture("office-change-short.yaml").string());
  scenario.camera.frame_rate_hz = 3.0;
  SimulateDataset(scenario, root / "office", {});
  const Dataset d = ReadDataset(root / "office");
  LocalizationOptions front_end;
  front_end.threads = 1;
  const MapVocabulary vocabulary = TrainMapVocabulary(d, {});
  const std::vector<Observation> observations = ExtractObservations(d, &vocabulary.vocabulary, nullptr, front_end);
  const FabMapModel model(vocabulary.vocabulary.tree(), FabMapOptions{});

  // The sweep's cell at the defaults is the front end's own run.
  InferenceSweepOptions sweep;
  sweep.front_end = front_end;
  sweep.d_tot_m = {1.0, 12.5};
  sweep.d_loc_m = {2.0};
  std::vector<std::size_t> progress;
  const std::vector<InferenceSweepCell> cells =
      RunInferenceSweep(d, observations, model, sweep, [&](std::size_t done, std::size_t total) {
        CHECK(total == 2);
        progress.push_back(done);
      });
  REQUIRE(cells.size() == 2);
  CHECK(progress == std::vector<std::size_t>{1, 2});
  CHECK(cells[0].d_tot_m == 1.0);
  CHECK(cells[1].d_tot_m == 12.5);
  const LocalizationResult direct = Localize(d, observations, model, front_end);
  int inferred = 0;
  for (const LoopClosure& c : direct.closures) inferred += c.kind == ClosureKind::kOdometryInferred;
  CHECK(inferred > 0);
  CHECK(cells[0].inferred == inferred);
  CHECK(cells[0].discarded + cells[0].dropped == direct.discarded_inferences.size());
  CHECK(cells[0].wrong == 0);  // the defaults make no inference over 1 m wrong here
  CHECK_FALSE(cells[0].false_accepted.has_value());
  sweep.false_threshold_m = 0.0;
  CHECK_THROWS_AS(RunInferenceSweep(d, observations, model, sweep), std::invalid_argument);

  // Four false matches, seed 1, cascade and flat.
  HierarchyExperimentOptions experiment;
  experiment.front_end = front_end;
  experiment.hierarchies = {"cascade", "flat"};
  experiment.seeds = {1};
  experiment.injection.count = 4;
  std::vector<std::string> seen;
  const std::vector<HierarchyExperimentRow> rows =
      RunHierarchyExperiment(d, observations, model, experiment,
                             [&](const HierarchyExperimentRow& row) { seen.push_back(row.hierarchy); });
  CHECK(seen == std::vector<std::string>{"cascade", "flat"});
  REQUIRE(rows.size() == 2);
  for (const HierarchyExperimentRow& row : rows) {
    CAPTURE(row.hierarchy);
    CHECK(row.seed == 1);
    CHECK(row.injection.parents == 8);  // a pair of false closures per match
    CHECK(row.ate_without_m > 0.0);
    CHECK(row.ate_with_m > 0.0);
    CHECK(row.ate_oracle_m > 0.0);
  }
  // Under cascade every child of a rejected false parent is turned off;
  // without a hierarchy some are kept.
  REQUIRE(rows[0].injection.children_of_rejected > 0);
  CHECK(rows[0].injection.children_of_rejected_accepted == 0);
  CHECK(rows[1].injection.children_of_rejected_accepted > 0);
  CHECK(rows[1].reruns == 0);  // flat is solved once
  experiment.hierarchies = {"sideways"};
  CHECK_THROWS_AS(RunHierarchyExperiment(d, observations, model, experiment), std::invalid_argument);
  std::filesystem::remove_all(root);
}

}  // namespace
}  // namespace catgraph
