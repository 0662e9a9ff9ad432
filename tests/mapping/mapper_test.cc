// The online Mapper against the offline pipeline on a simulated office: the
// same front end frame by frame, closures reported as they are made, online
// solves that correct the map as the robot drives, and the offline map from
// Solve().
#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
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
          "[mapping][slow]") {
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

  // The offline pipeline; its front end (before any feedback re-run) makes
  // the closures the stream made.
  const MappingResult mapped = MapDataset(d, observations, model, front_end, options.back_end, options.hierarchy);
  const LocalizationResult offline = mapped.reruns == 0 ? mapped.front : Localize(d, observations, model, front_end);
  REQUIRE(streamed.size() == offline.closures.size());
  for (std::size_t i = 0; i < streamed.size(); ++i) {
    CHECK(streamed[i].id == offline.closures[i].id);
    CHECK(streamed[i].frame == offline.closures[i].frame);
    CHECK(streamed[i].matched_frame == offline.closures[i].matched_frame);
  }
  CHECK(mapper.front_end().graph.constraints.size() == offline.graph.constraints.size());

  // The online map, corrected as the closures came, against the truth and
  // the offline pipeline; Solve() is its first solve.
  const MapOutcome final_solve = mapper.Solve(truth);
  REQUIRE(final_solve.ate_corrected);
  REQUIRE(mapped.first.ate_corrected);
  CHECK(final_solve.ate_corrected->ate_m.rmse == mapped.first.ate_corrected->ate_m.rmse);
  CHECK(final_solve.solved.optimization.accepted == mapped.first.solved.optimization.accepted);
  // Feedback re-runs only when the back end rejected a visual closure.
  const bool rejected_visual = std::any_of(offline.closures.begin(), offline.closures.end(), [&](const LoopClosure& c) {
    return c.kind == ClosureKind::kVisual && !mapped.first.decision_of.at(ClosureId(c.id)).accepted;
  });
  CHECK((mapped.reruns > 0) == rejected_visual);
  const double ate_online = AteOf(mapper.Map(), truth);
  const double ate_odometry = final_solve.ate_odometry->ate_m.rmse;
  CAPTURE(ate_online, ate_odometry, final_solve.ate_corrected->ate_m.rmse, solves);
  CHECK(ate_online < 0.5 * ate_odometry);
  CHECK(ate_online <= 1.1 * final_solve.ate_corrected->ate_m.rmse);
  std::filesystem::remove_all(root);
}

// A ring of 30 m driven once and then 10 m further, a frame every 0.1 m;
// each 0.5 m stretch has 4 words of its own, seen with 80 % chance each. The
// odometry turns 0.003 rad a frame too far, so dead reckoning is 0.9 rad off
// when the ring closes: only the closures put it back.
struct Ring {
  static constexpr double kStep = 0.1, kCircumference = 30.0;
  static constexpr int kFramesPerLap = 300, kFrames = 400;
  std::mt19937_64 rng{7};
  Observation Observe(int frame) {
    const int bin = static_cast<int>(std::fmod(frame * kStep, kCircumference) / 0.5);
    Observation z;
    for (int k = 0; k < 4; ++k) {
      if (std::uniform_real_distribution<double>(0, 1)(rng) < 0.8) z.words.push_back(4 * bin + k);
    }
    return z;
  }
  static Pose2 Truth(int frame) {
    const double radius = kCircumference / (2.0 * std::numbers::pi), phi = frame * kStep / radius;
    return {radius * std::sin(phi), radius * (1.0 - std::cos(phi)), phi};
  }
  static Pose2 OdometryStep(int frame) {
    Pose2 step = Truth(frame - 1).Between(Truth(frame));
    return {step.x(), step.y(), step.theta() + 0.003};
  }
};

TEST_CASE("on a ring the Mapper reports each closure at its frame, re-solves when closures come and corrects the "
          "drift",
          "[mapping]") {
  Ring ring;
  std::vector<WordSet> lap;
  for (int k = 0; k < Ring::kFramesPerLap; ++k) lap.push_back(ring.Observe(k).words);
  const FabMapModel model(LearnChowLiuTree(lap, 4 * 60), FabMapOptions{});
  MapperOptions options;
  options.front_end.filter.num_particles = 500;
  options.front_end.filter.new_place.log_offset = 0.0;  // 3 words a frame, not a real image's 70
  // Switchable constraints solve online on one growing problem
  // (OnlineBackEnd); another method re-solves from scratch each time.
  options.back_end.method = GENERATE(RobustMethod::kSwitchable, RobustMethod::kNone, RobustMethod::kGnc);
  CAPTURE(ToString(options.back_end.method));
  Mapper mapper(model, options);
  Localizer offline(model, options.front_end);
  Pose2 odometry;
  Trajectory2 truth, dead_reckoning;
  std::vector<LoopClosure> streamed;
  int solves = 0;
  for (int k = 0; k < Ring::kFrames; ++k) {
    if (k > 0) odometry = odometry * Ring::OdometryStep(k);
    const Observation z = ring.Observe(k);
    const FrameInput in(0.25 * k, odometry, 1 + k / Ring::kFramesPerLap, Ring::Truth(k));
    const FrameResult r = mapper.AddFrame(in, z);
    const FrameLocalization alone = offline.AddFrame(in, z);
    CHECK(r.localization.closure == alone.closure);
    CHECK(r.localization.matched_frame == alone.matched_frame);
    CHECK(r.solve.has_value() == !r.closures.empty());
    if (r.solve) ++solves;
    for (const LoopClosure& c : r.closures) {
      if (c.kind == ClosureKind::kVisual) CHECK(c.frame == k);
      CHECK(c.error_m <= 1.0);
      streamed.push_back(c);
    }
    truth.emplace(PoseId(k), Ring::Truth(k));
    dead_reckoning.emplace(PoseId(k), odometry);
    if (solves == 0) CHECK(testing::ApproxEqual(mapper.Map().at(PoseId(k)), odometry));
  }
  REQUIRE(solves > 10);
  REQUIRE(streamed.size() == offline.result().closures.size());
  for (std::size_t i = 0; i < streamed.size(); ++i) CHECK(streamed[i].id == offline.result().closures[i].id);
  CHECK(mapper.decisions().size() == streamed.size());
  // The drift corrected online, and as the offline solve corrects it.
  const double ate_odometry = AteOf(dead_reckoning, truth), ate_online = AteOf(mapper.Map(), truth);
  const MapOutcome final_solve = mapper.Solve(truth);
  REQUIRE(final_solve.ate_corrected);
  const double ate_final = final_solve.ate_corrected->ate_m.rmse;
  CAPTURE(ate_odometry, ate_online, ate_final, solves, streamed.size());
  CHECK(ate_online < 0.2 * ate_odometry);
  CHECK(ate_online <= 1.1 * ate_final + 0.01);
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
  gate.back_end.gate.probability = 1.0;
  CHECK_THROWS_WITH(Mapper(model, gate), Catch::Contains("gate.probability"));
  MapperOptions iterations;
  iterations.online_max_iterations = 0;
  CHECK_THROWS_WITH(Mapper(model, iterations), Catch::Contains("online_max_iterations"));
  MapperOptions filter;
  filter.front_end.filter.num_particles = 0;
  CHECK_THROWS_AS(Mapper(model, filter), std::invalid_argument);
}

}  // namespace
}  // namespace catgraph::mapping
