// Trajectory and closure scores: analytic cases, invariances, and the
// published reference values of robust-backend-notes.md §3.
#include <numbers>
#include <random>

#include "tests/catch.h"

#include "backend/evaluation.h"
#include "backend/io/graph_io.h"
#include "backend/io/trajectory_io.h"
#include "backend/pose_graph_optimizer.h"
#include "tests/test_support.h"

namespace catgraph {
namespace {

template <typename PoseT, typename Draw>
Trajectory<PoseT> RandomTrajectory(int n, Draw draw) {
  Trajectory<PoseT> t;
  for (int i = 0; i < n; ++i) t[PoseId(i)] = draw();
  return t;
}

TEST_CASE("error statistics of a known list", "[evaluation]") {
  const ErrorStatistics s = StatisticsOf({4.0, 1.0, 3.0, 2.0});
  CHECK(s.count == 4);
  CHECK(s.mean == Approx(2.5));
  CHECK(s.median == Approx(2.5));
  CHECK(s.max == 4.0);
  CHECK(s.rmse == Approx(std::sqrt(7.5)));
  CHECK(StatisticsOf({3.0, 1.0, 2.0}).median == 2.0);
  CHECK(StatisticsOf({}).count == 0);
}

TEST_CASE("a rigidly moved copy of the truth has zero ATE and zero RPE, in 2D and 3D",
          "[evaluation]") {
  std::mt19937_64 rng(3);
  const auto truth2 = RandomTrajectory<Pose2>(60, [&] { return testing::RandomPose2(rng); });
  const Pose2 move2 = testing::RandomPose2(rng);
  Trajectory2 est2;
  for (const auto& [id, p] : truth2) est2[id] = move2 * p;
  const TrajectoryEvaluation e2 = EvaluateTrajectory(est2, truth2);
  CHECK(e2.poses == 60);
  CHECK(e2.ate_m.rmse == Approx(0.0).margin(1e-9));
  CHECK(e2.rmse_anchored_m == Approx(0.0).margin(1e-9));
  CHECK(e2.rpe_translation_m.max == Approx(0.0).margin(1e-9));
  CHECK(e2.rpe_rotation_rad.max == Approx(0.0).margin(1e-9));

  const auto truth3 = RandomTrajectory<Pose3>(60, [&] { return testing::RandomPose3(rng); });
  const Pose3 move3 = testing::RandomPose3(rng);
  Trajectory3 est3;
  for (const auto& [id, p] : truth3) est3[id] = move3 * p;
  const TrajectoryEvaluation e3 = EvaluateTrajectory(est3, truth3);
  CHECK(e3.ate_m.rmse == Approx(0.0).margin(1e-9));
  CHECK(e3.rmse_anchored_m == Approx(0.0).margin(1e-9));
  CHECK(e3.rpe_rotation_rad.max == Approx(0.0).margin(1e-9));
}

TEST_CASE("the alignment of a rigidly moved copy is the inverse move, in 2D and 3D", "[evaluation]") {
  std::mt19937_64 rng(5);
  const auto truth2 = RandomTrajectory<Pose2>(40, [&] { return testing::RandomPose2(rng); });
  const Pose2 move2 = testing::RandomPose2(rng);
  Trajectory2 est2;
  for (const auto& [id, p] : truth2) est2[id] = move2 * p;
  const Pose2 undo2 = AlignmentOnto(est2, truth2) * move2;  // the identity
  CHECK(undo2.x() == Approx(0.0).margin(1e-9));
  CHECK(undo2.y() == Approx(0.0).margin(1e-9));
  CHECK(undo2.theta() == Approx(0.0).margin(1e-9));

  const auto truth3 = RandomTrajectory<Pose3>(40, [&] { return testing::RandomPose3(rng); });
  const Pose3 move3 = testing::RandomPose3(rng);
  Trajectory3 est3;
  for (const auto& [id, p] : truth3) est3[id] = move3 * p;
  const Pose3 undo3 = AlignmentOnto(est3, truth3) * move3;
  CHECK(undo3.translation().norm() == Approx(0.0).margin(1e-9));
  CHECK(RotationAngle(undo3.rotation()) == Approx(0.0).margin(1e-9));
  CHECK_THROWS_AS(AlignmentOnto(Trajectory2{{PoseId(0), Pose2()}}, truth2), std::invalid_argument);
}

TEST_CASE("ATE after the optimal alignment is never above the anchored RMSE", "[evaluation]") {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 0.3);
  for (int trial = 0; trial < 20; ++trial) {
    const auto truth = RandomTrajectory<Pose2>(40, [&] { return testing::RandomPose2(rng); });
    Trajectory2 est;
    for (const auto& [id, p] : truth) est[id] = Pose2(p.x() + noise(rng), p.y() + noise(rng), p.theta());
    const TrajectoryEvaluation e = EvaluateTrajectory(est, truth);
    CHECK(e.ate_m.rmse <= e.rmse_anchored_m + 1e-12);
    CHECK(e.ate_m.rmse > 0.0);
  }
}

TEST_CASE("analytic ATE and RPE on a straight line", "[evaluation]") {
  // Truth: unit steps along x. Estimate: steps of 1.1 m. Anchored error of
  // pose k is 0.1 k; every RPE step is 0.1 m with no rotation.
  Trajectory2 truth, est;
  double sum_sq = 0.0;
  for (int k = 0; k < 11; ++k) {
    truth[PoseId(k)] = Pose2(k, 0.0, 0.0);
    est[PoseId(k)] = Pose2(1.1 * k, 0.0, 0.0);
    sum_sq += 0.01 * k * k;
  }
  const TrajectoryEvaluation e = EvaluateTrajectory(est, truth);
  CHECK(e.rmse_anchored_m == Approx(std::sqrt(sum_sq / 11.0)));
  CHECK(e.rpe_translation_m.rmse == Approx(0.1));
  CHECK(e.rpe_rotation_rad.max == Approx(0.0).margin(1e-12));
  // Aligned without scale, the best fit centres the stretch: errors 0.1 |k - 5|.
  double aligned_sq = 0.0;
  for (int k = 0; k < 11; ++k) aligned_sq += 0.01 * (k - 5) * (k - 5);
  CHECK(e.ate_m.rmse == Approx(std::sqrt(aligned_sq / 11.0)));
  CHECK(e.ate_m.max == Approx(0.5));
}

TEST_CASE("a pose without ground truth is an error naming it", "[evaluation]") {
  Trajectory2 truth{{PoseId(0), Pose2()}, {PoseId(1), Pose2(1, 0, 0)}};
  Trajectory2 est = truth;
  est[PoseId(7)] = Pose2();
  CHECK_THROWS_WITH(EvaluateTrajectory(est, truth), Catch::Contains("pose 7"));
  // A 2D truth scores a 3D estimate of the same plane, and the reverse.
  const AnyTrajectory planar3 = ConvertTrajectory<Pose3>(truth);
  CHECK(EvaluateTrajectory(AnyTrajectory(truth), planar3).ate_m.rmse == Approx(0.0).margin(1e-12));
}

TEST_CASE("closure scores count matches by endpoints, in order, absent ones rejected",
          "[evaluation]") {
  auto label = [](std::int64_t from, std::int64_t to, bool outlier) {
    ClosureLabel l;
    l.from = PoseId(from);
    l.to = PoseId(to);
    l.outlier = outlier;
    return l;
  };
  // (0,5) twice: the true original first, the injected copy second.
  const std::vector<ClosureLabel> labels = {label(0, 5, false), label(2, 9, false),
                                            label(3, 7, false), label(0, 5, true),
                                            label(4, 8, true), label(1, 6, true)};
  const std::vector<ClosureOutcome> outcomes = {
      {PoseId(5), PoseId(0), true},   // reversed direction still matches
      {PoseId(2), PoseId(9), false},  // a true closure rejected
      {PoseId(3), PoseId(7), true},   {PoseId(0), PoseId(5), false},
      {PoseId(4), PoseId(8), true}};  // (1, 6) absent: rejected
  const ClosureScores s = ScoreClosures(outcomes, labels);
  CHECK(s.true_positives == 2);
  CHECK(s.false_negatives == 1);
  CHECK(s.false_positives == 1);
  CHECK(s.true_negatives == 2);
  CHECK(s.precision == Approx(2.0 / 3.0));
  CHECK(s.recall == Approx(2.0 / 3.0));
  CHECK(s.f1 == Approx(2.0 / 3.0));
  // Nothing accepted: precision 1 by convention, recall 0, F1 0.
  const ClosureScores none = ScoreClosures({}, labels);
  CHECK(none.precision == 1.0);
  CHECK(none.recall == 0.0);
  CHECK(none.f1 == 0.0);
}

TEST_CASE("an outlier the ground truth explains is told apart from one it contradicts",
          "[evaluation]") {
  // Truth: a 2 m square of poses 0..3. Closures 0-2 and 1-3 are labelled
  // false; 0-2's measurement is the true relative pose (chi2 0 at the
  // truth), 1-3's is 1 m off (chi2 = 1 * 100 with information 100).
  Trajectory2 truth = {{PoseId(0), Pose2(0, 0, 0)},
                       {PoseId(1), Pose2(2, 0, std::numbers::pi / 2)},
                       {PoseId(2), Pose2(2, 2, std::numbers::pi)},
                       {PoseId(3), Pose2(0, 2, -std::numbers::pi / 2)}};
  PoseGraph2 graph;
  for (const auto& [id, pose] : truth) graph.vertices[id] = {id, pose, false};
  auto closure = [&](std::int64_t from, std::int64_t to, const Pose2& z) {
    Constraint<Pose2> c;
    c.id = ClosureId(static_cast<std::int64_t>(graph.constraints.size()));
    c.from = PoseId(from);
    c.to = PoseId(to);
    c.measurement.mean = z;
    c.measurement.information = 100.0 * Eigen::Matrix3d::Identity();
    graph.constraints.push_back(c);
  };
  closure(0, 2, truth[PoseId(0)].Between(truth[PoseId(2)]));
  const Pose2 true_13 = truth[PoseId(1)].Between(truth[PoseId(3)]);
  closure(1, 3, Pose2(true_13.x() + 1.0, true_13.y(), true_13.theta()));
  auto label = [](std::int64_t from, std::int64_t to) {
    ClosureLabel l;
    l.from = PoseId(from);
    l.to = PoseId(to);
    l.outlier = true;
    return l;
  };
  const std::vector<ClosureLabel> labels = {label(0, 2), label(1, 3)};
  for (const bool second_accepted : {false, true}) {
    CAPTURE(second_accepted);
    std::vector<ClosureOutcome> outcomes = {{PoseId(2), PoseId(0), true},
                                            {PoseId(1), PoseId(3), second_accepted}};
    AttachChi2AtTruth(outcomes, AnyPoseGraph(graph), AnyTrajectory(truth));
    CHECK(outcomes[0].chi2_at_truth == Approx(0.0).margin(1e-18));
    CHECK(outcomes[1].chi2_at_truth == Approx(100.0));
    const ClosureScores s = ScoreClosures(outcomes, labels, 16.27);
    CHECK(s.outliers_explained_by_truth == 1);
    CHECK(s.explained_outliers_accepted == 1);
    CHECK(s.outlier_rejection == Approx(second_accepted ? 0.0 : 0.5));
    CHECK(s.unexplained_outlier_rejection == Approx(second_accepted ? 0.0 : 1.0));
    // Without a truth gate nothing counts as explained.
    CHECK(ScoreClosures(outcomes, labels).outliers_explained_by_truth == 0);
  }
  // A truth without an endpoint leaves the chi2 unknown, and unexplained.
  truth.erase(PoseId(3));
  std::vector<ClosureOutcome> outcomes = {{PoseId(1), PoseId(3), false}};
  AttachChi2AtTruth(outcomes, AnyPoseGraph(graph), AnyTrajectory(truth));
  CHECK(std::isnan(outcomes[0].chi2_at_truth));
}

TEST_CASE("the outlier-free Manhattan optimum: ATE 0.79 m, anchored RMSE 1.18 m "
          "(robust-backend-notes.md)",
          "[evaluation][shared]") {
  CATGRAPH_SHARED_POSE_GRAPHS_OR_SKIP(root);
  const auto manhattan = root / "vertigo/manhattan";
  const AnyTrajectory truth =
      ReadTrajectoryFile(manhattan / "groundTruth/manhattanOlson3500_nodes_groundTruth.dat");
  for (const char* file : {"originalDataset/Olson/manhattanOlson3500.g2o",
                           "originalDataset/g2o/manhattanOlson3500.g2o"}) {
    PoseGraphOptimizerOptions options;
    options.method = RobustMethod::kNone;
    const PoseGraphOptimization r = OptimizePoseGraph(ReadGraphFile(manhattan / file).graph, options);
    REQUIRE(r.summary.IsUsable());
    const TrajectoryEvaluation e = EvaluateTrajectory(TrajectoryOf(r.graph), truth);
    CAPTURE(file);
    CHECK(e.poses == 3500);
    CHECK(e.ate_m.rmse == Approx(0.79).margin(0.01));
    CHECK(e.rmse_anchored_m == Approx(1.18).margin(0.01));
  }
}

TEST_CASE("the ring optimum: ATE 1.43 m, anchored RMSE 4.39 m (robust-backend-notes.md)",
          "[evaluation][shared]") {
  CATGRAPH_SHARED_POSE_GRAPHS_OR_SKIP(root);
  PoseGraphOptimizerOptions options;
  options.method = RobustMethod::kNone;
  const PoseGraphOptimization r = OptimizePoseGraph(
      ReadGraphFile(root / "vertigo/ring/originalDataset/ring.g2o").graph, options);
  REQUIRE(r.summary.IsUsable());
  const TrajectoryEvaluation e = EvaluateTrajectory(
      TrajectoryOf(r.graph), ReadTrajectoryFile(root / "vertigo/ring/groundTruth/poses.txt"));
  CHECK(e.ate_m.rmse == Approx(1.43).margin(0.01));
  CHECK(e.rmse_anchored_m == Approx(4.39).margin(0.01));
}

}  // namespace
}  // namespace catgraph
