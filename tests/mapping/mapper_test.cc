// The online Mapper against the offline pipeline on a simulated office: the
// same front end frame by frame, closures reported as they are made, online
// solves that correct the map as the robot drives, and the offline map from
// Solve().
#include <algorithm>
#include <cmath>
#include <vector>

#include "backend/evaluation.h"
#include "backend/io/dataset.h"
#include "frontend/fabmap.h"
#include "frontend/holistic.h"
#include "frontend/localization.h"
#include "mapping/map_dataset.h"
#include "mapping/mapper.h"
#include "simulation/office_simulator.h"
#include "simulation/scenario.h"
#include "tests/catch.h"
#include "tests/test_support.h"

namespace catgraph::mapping {
namespace {

// The short office of tests/fixtures at 3 frames/s: 375 frames, two
// traversals, a changed corridor.
Dataset SmallOffice(const std::filesystem::path& root) {
  Scenario scenario = LoadScenario(testing::Fixture("office-change-short.yaml").string());
  scenario.camera.frame_rate_hz = 3.0;
  SimulateDataset(scenario, root / "office", {});
  return ReadDataset(root / "office");
}

FrameInput InputOf(const Dataset& d, const std::vector<Pose2>& odometry, const std::vector<Pose2>& truth,
                   std::size_t k) {
  FrameInput in;
  in.time_s = d.frames[k].timestamp_s;
  in.odometry = odometry[k];
  in.traversal = d.frames[k].traversal;
  in.truth = truth[k];
  return in;
}

double AteOf(const Trajectory2& estimate, const Trajectory2& truth) {
  return EvaluateTrajectory(estimate, truth).ate_m.rmse;
}

TEST_CASE("the Mapper streams a dataset as the offline pipeline maps it, correcting the map as closures come",
          "[mapping][small-office]") {
  const auto root = testing::TempDir("mapper");
  const Dataset d = SmallOffice(root);
  REQUIRE(d.frames.size() == 375);
  LocalizationOptions front_end;
  front_end.threads = 1;
  const MapVocabulary vocabulary = TrainMapVocabulary(d, {});
  const std::vector<Observation> observations = ExtractObservations(d, &vocabulary.vocabulary, nullptr, front_end);
  const FabMapModel model(vocabulary.vocabulary.tree(), FabMapOptions{});
  const std::vector<Pose2> odometry = PosesAtFrames(d, d.odometry), truth_at = PosesAtFrames(d, d.ground_truth);
  const Trajectory2 truth = TruthAtFrames(d);

  MapperOptions options;
  options.front_end = front_end;
  Mapper mapper(model, options);
  std::vector<LoopClosure> streamed;
  int solves = 0;
  for (std::size_t k = 0; k < d.frames.size(); ++k) {
    const FrameResult r = mapper.AddFrame(InputOf(d, odometry, truth_at, k), observations[k]);
    CHECK(r.localization.frame == static_cast<int>(k));
    // A solve exactly when closures came, each made at this frame.
    CHECK(r.solve.has_value() == !r.closures.empty());
    for (const LoopClosure& c : r.closures) {
      CHECK((c.kind == ClosureKind::kVisual ? c.frame : r.closures.front().frame) == static_cast<int>(k));
      streamed.push_back(c);
    }
    if (r.solve) {
      ++solves;
      CHECK(r.solve->accepted + r.solve->rejected == static_cast<int>(streamed.size()));
    } else if (solves == 0) {
      // Before any closure the map is the odometry.
      const Trajectory2 map = mapper.Map();
      REQUIRE(map.size() == k + 1);
      CHECK(testing::ApproxEqual(map.rbegin()->second, odometry[k]));
    }
  }
  REQUIRE(solves > 0);

  // The same front end as the offline Localize.
  const LocalizationResult offline = Localize(d, observations, model, front_end);
  REQUIRE(streamed.size() == offline.closures.size());
  for (std::size_t i = 0; i < streamed.size(); ++i) {
    CHECK(streamed[i].id == offline.closures[i].id);
    CHECK(streamed[i].frame == offline.closures[i].frame);
    CHECK(streamed[i].matched_frame == offline.closures[i].matched_frame);
  }
  CHECK(mapper.front_end().graph.constraints.size() == offline.graph.constraints.size());

  // The online map, corrected as the closures came, against the truth and
  // the offline solve; Solve() is the offline solve.
  const MapOutcome final_solve = mapper.Solve(truth);
  const MapOutcome first_offline = SolveMap(offline, options.back_end, options.hierarchy, truth);
  REQUIRE(final_solve.ate_corrected);
  CHECK(final_solve.ate_corrected->ate_m.rmse == first_offline.ate_corrected->ate_m.rmse);
  const double ate_online = AteOf(mapper.Map(), truth);
  const double ate_odometry = final_solve.ate_odometry->ate_m.rmse;
  CAPTURE(ate_online, ate_odometry, final_solve.ate_corrected->ate_m.rmse, solves);
  CHECK(ate_online < 0.5 * ate_odometry);
  CHECK(ate_online <= 1.1 * final_solve.ate_corrected->ate_m.rmse);
  std::filesystem::remove_all(root);
}

TEST_CASE("the Mapper refuses options out of range", "[mapping]") {
  const HolisticModel model({}, HolisticCalibration{});
  MapperOptions coupled;
  coupled.hierarchy.policy = HierarchyPolicy::kCoupled;
  coupled.back_end.method = RobustMethod::kDcs;
  CHECK_THROWS_WITH(Mapper(model, coupled), Catch::Contains("switchable"));
  MapperOptions uncertainty;
  uncertainty.front_end.graph_uncertainty.closure_sigma.x() = 0.0;
  CHECK_THROWS_WITH(Mapper(model, uncertainty), Catch::Contains("PoseGraphUncertainty"));
  MapperOptions gate;
  gate.back_end.switch_gate_probability = 1.0;
  CHECK_THROWS_WITH(Mapper(model, gate), Catch::Contains("switch_gate_probability"));
  MapperOptions filter;
  filter.front_end.filter.num_particles = 0;
  CHECK_THROWS_AS(Mapper(model, filter), std::invalid_argument);
}

}  // namespace
}  // namespace catgraph::mapping
