// False visual matches at the source: the plan against the definition
// (false by ground truth, same shape by odometry, inside the gate, apart),
// and the filter taking a stretch for the wrong one.
#include <cmath>
#include <map>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "tests/catch.h"

#include "experiments/false_matches.h"
#include "frontend/localization.h"

namespace catgraph {
namespace {

// Two laps of a 20 m x 10 m rectangle, a frame every 0.1 m at 1 m/s, the
// laps 30 s apart (a sequence break); odometry turns 0.2 % too far.
Dataset RectangleLaps() {
  Dataset d;
  std::vector<Pose2> truth_steps;
  for (const double side : {20.0, 10.0, 20.0, 10.0}) {
    for (int i = 0; i < static_cast<int>(std::lround(side / 0.1)); ++i) truth_steps.emplace_back(0.1, 0.0, 0.0);
    truth_steps.back() = Pose2(0.1, 0.0, std::numbers::pi / 2);
  }
  double t = 0.0;
  for (int lap = 1; lap <= 2; ++lap) {
    Pose2 truth, odometry;
    for (const Pose2& step : truth_steps) {
      d.frames.push_back({t, "", lap, false, 0.0});
      d.ground_truth.push_back({t, truth});
      d.odometry.push_back({t, odometry});
      truth = truth * step;
      odometry = odometry * Pose2(step.x(), step.y(), 1.002 * step.theta());
      t += 0.1;
    }
    t += 30.0;
  }
  return d;
}

double PathBetween(const std::vector<TimedPose2>& poses, int a, int b) {
  double path = 0.0;
  for (int k = a; k < b; ++k) {
    path += (poses[static_cast<std::size_t>(k + 1)].pose.translation() - poses[static_cast<std::size_t>(k)].pose.translation()).norm();
  }
  return path;
}

TEST_CASE("false visual matches are false, of the old stretch's shape, inside the gate and apart",
          "[experiments][false-matches]") {
  const Dataset d = RectangleLaps();
  const CatGraphOptions filter;
  FalseMatchOptions o;
  o.count = 6;
  o.seed = 7;
  const std::vector<FalseVisualMatch> plan = PlanFalseVisualMatches(d, filter, o);
  REQUIRE(plan.size() == 6);
  auto truth = [&](int k) { return d.ground_truth[static_cast<std::size_t>(k)].pose; };
  auto odometry = [&](int k) { return d.odometry[static_cast<std::size_t>(k)].pose; };
  for (std::size_t m = 0; m < plan.size(); ++m) {
    const FalseVisualMatch& f = plan[m];
    CAPTURE(m, f.first_frame, f.last_frame, f.matched_first_frame, f.matched_last_frame);
    CHECK(f.first_frame < f.last_frame);
    CHECK(f.matched_first_frame < f.matched_last_frame);
    CHECK(f.matched_last_frame < f.first_frame);
    // The whole stretch in one lap, and long as asked.
    CHECK(d.frames[static_cast<std::size_t>(f.first_frame)].traversal ==
          d.frames[static_cast<std::size_t>(f.last_frame)].traversal);
    CHECK(PathBetween(d.odometry, f.first_frame, f.last_frame) == Approx(o.stretch_m).margin(0.1 + 1e-9));
    // False at both ends by ground truth.
    CHECK((truth(f.first_frame).translation() - truth(f.matched_first_frame).translation()).norm() >= o.min_error_m);
    CHECK((truth(f.last_frame).translation() - truth(f.matched_last_frame).translation()).norm() >= o.min_error_m);
    // The same shape by odometry.
    const Pose2 now = odometry(f.first_frame).Between(odometry(f.last_frame));
    const Pose2 then = odometry(f.matched_first_frame).Between(odometry(f.matched_last_frame));
    CHECK((now.translation() - then.translation()).norm() <= o.shape_tolerance_m);
    CHECK(std::abs(WrapAngle(now.theta() - then.theta())) <= o.shape_tolerance_rad);
    // Inside the odometric gate with d_h to spare.
    const double since = PathBetween(d.odometry, f.matched_first_frame, f.first_frame);
    CHECK((odometry(f.first_frame).translation() - odometry(f.matched_first_frame).translation()).norm() <=
          OdometricGateRadius(filter, since) - filter.hypothesis_radius_m);
    // Sorted and apart.
    if (m > 0) {
      CHECK(plan[m - 1].last_frame < f.first_frame);
      CHECK(PathBetween(d.odometry, plan[m - 1].last_frame, f.first_frame) >= o.separation_m);
    }
  }
  // One seed, one plan; another seed, another.
  CHECK(PlanFalseVisualMatches(d, filter, o).front().first_frame == plan.front().first_frame);
  o.seed = 8;
  const std::vector<FalseVisualMatch> other = PlanFalseVisualMatches(d, filter, o);
  bool differs = false;
  for (std::size_t m = 0; m < plan.size(); ++m) differs |= other[m].first_frame != plan[m].first_frame;
  CHECK(differs);
}

TEST_CASE("false visual matches need ground truth, sane options and room", "[experiments][false-matches][bad-input]") {
  Dataset d = RectangleLaps();
  FalseMatchOptions o;
  o.count = 0;
  CHECK(PlanFalseVisualMatches(d, CatGraphOptions{}, o).empty());
  o.count = 1000;
  CHECK_THROWS_WITH(PlanFalseVisualMatches(d, CatGraphOptions{}, o), Catch::Contains("only"));
  o.count = 1;
  o.max_error_m = 1.0;  // below the minimum
  CHECK_THROWS_AS(PlanFalseVisualMatches(d, CatGraphOptions{}, o), std::invalid_argument);
  o.max_error_m = 1e9;
  d.ground_truth.clear();
  CHECK_THROWS_WITH(PlanFalseVisualMatches(d, CatGraphOptions{}, o), Catch::Contains("ground truth"));
}

TEST_CASE("a plan is imposed as forced ends and withheld closures between them, frame by frame",
          "[experiments][false-matches]") {
  const std::vector<FalseVisualMatch> plan = {{20, 23, 5, 8}, {30, 31, 2, 3}};
  const std::map<int, ClosureOverride> imposed = ImposedDecisions(plan);
  CHECK(imposed.size() == 6);
  for (const auto& [frame, d] : imposed) {
    CAPTURE(frame);
    CHECK(d.withhold);
    CHECK_FALSE(d.vetoed);
  }
  CHECK(imposed.at(20).force_node == 5);
  CHECK(imposed.at(21).force_node == -1);
  CHECK(imposed.at(22).force_node == -1);
  CHECK(imposed.at(23).force_node == 8);
  CHECK(imposed.at(30).force_node == 2);
  CHECK(imposed.at(31).force_node == 3);
  CHECK(ImposedDecisions({}).empty());

  CHECK_THROWS_WITH(ImposedDecisions({{20, 23, 5, 8}, {23, 25, 1, 2}}), Catch::Contains("overlap at frame 23"));
  CHECK_THROWS_AS(ImposedDecisions({{20, 20, 5, 8}}), std::invalid_argument);   // first < last
  CHECK_THROWS_AS(ImposedDecisions({{20, 23, 21, 8}}), std::invalid_argument);  // onto an older frame
  CHECK_THROWS_AS(ImposedDecisions({{20, 23, -1, 8}}), std::invalid_argument);
  LocalizationOptions options;
  options.imposed[-1] = {};
  CHECK_THROWS_AS(Validate(options), std::invalid_argument);
}

}  // namespace
}  // namespace catgraph
