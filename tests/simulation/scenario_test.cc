// Scenario files: the built-in ones parse, and every mistake in a file is an
// error that names the file and the line.
#include <string>

#include "tests/catch.h"

#include "backend/io/file_error.h"
#include "simulation/scenario.h"

namespace catgraph {
namespace {

std::string ScenarioError(const std::string& yaml) {
  try {
    ParseScenario(yaml, "my.yaml", ".");
  } catch (const FileError& e) {
    return e.what();
  }
  return "no error";
}

constexpr const char* kMinimal =
    "name: tiny\n"
    "world: {building: [0, 0, 10, 4], blocks: [[0, 2, 10, 4]]}\n"
    "traversals:\n"
    "  - {id: 1, route: [[1, 1], [9, 1]]}\n"
    "  - {id: 2, route: [[9, 1], [1, 1]]}\n";

TEST_CASE("the built-in scenarios parse and agree with their documentation", "[simulation][scenario]") {
  const auto names = BuiltInScenarioNames();
  REQUIRE(names == std::vector<std::string>{"office-static", "office-change", "office-split", "office-lighting",
                                            "office-training"});
  for (const auto& name : names) {
    INFO(name);
    const Scenario s = LoadScenario(name);
    CHECK(s.name == name);
    CHECK(s.traversals.size() == (name == "office-training" ? 1u : 2u));
    // The training world is the same building redecorated.
    CHECK(s.floor_plan.texture_seed == (name == "office-training" ? 1001u : 7u));
    CHECK(s.floor_plan.building.x1 - s.floor_plan.building.x0 == 60.0);
    CHECK(s.floor_plan.building.y1 - s.floor_plan.building.y0 == 30.0);
    CHECK(s.camera.width_px == 261);
    CHECK(s.camera.height_px == 101);
    CHECK(s.camera.frame_rate_hz == 7.5);
    CHECK(s.odometry.rate_hz == 10.0);
  }
  const Scenario change = LoadScenario("office-change");
  int added = 0, removed = 0;
  for (const auto& f : change.furniture) {
    added += f.traversals == std::vector<int>{2};
    removed += f.traversals == std::vector<int>{1};
  }
  CHECK(added == 13);
  CHECK(removed == 3);
}

TEST_CASE("a minimal scenario takes the documented defaults", "[simulation][scenario]") {
  const Scenario s = ParseScenario(kMinimal, "my.yaml", ".");
  CHECK(s.seed == 1);
  CHECK(s.traversals.front().speed_m_s == 0.4);
  CHECK(s.changed_pixel_fraction == 0.1);
  CHECK(s.floor_plan.ceiling_height_m == 2.7);
}

TEST_CASE("scenario mistakes name the file and the line", "[simulation][scenario][bad-input]") {
  std::string yaml = kMinimal;
  CHECK_THAT(ScenarioError(yaml + "colour: red\n"), Catch::Contains("my.yaml:6: unknown key 'colour'"));
  CHECK_THAT(ScenarioError(yaml + "camera: {width_px: -3}\n"), Catch::Contains("my.yaml:6: camera: width_px: expected an integer in [2, 8192]"));
  CHECK_THAT(ScenarioError(yaml + "seed: [1\n"), Catch::Contains("my.yaml:"));
  CHECK_THAT(ScenarioError(yaml + "camera: {hfov_deg: wide}\n"), Catch::Contains("my.yaml:6: camera: hfov_deg: expected a number"));
  // A route through the block.
  std::string through = kMinimal;
  through.replace(through.find("[9, 1]"), 6, "[9, 3]");
  CHECK_THAT(ScenarioError(through), Catch::Contains("my.yaml:4: traversal 1: the route passes within"));
  // A route that stays at one point (a fuzzer's find: it escaped as std::invalid_argument).
  std::string still = kMinimal;
  still.replace(still.find("[9, 1]"), 6, "[1.0, 1]");
  CHECK_THAT(ScenarioError(still), Catch::Contains("my.yaml:4: traversal 1: route: expected at least 2 distinct waypoints"));
  // Furniture that changes outside every changed region.
  CHECK_THAT(ScenarioError(yaml + "furniture:\n  - {name: crate, style: boxes, box: [4, 0.1, 5, 0.5], traversals: [1]}\n"), Catch::Contains("my.yaml:7: furniture 'crate' does not stand in every traversal"));
  CHECK_THAT(ScenarioError(yaml + "furniture:\n  - {name: crate, style: crates, box: [4, 0.1, 5, 0.5], traversals: [1]}\n"), Catch::Contains("unknown furniture style 'crates'"));
  CHECK_THAT(ScenarioError("name: x\nworld: atlantis\ntraversals: []\n"), Catch::Contains("my.yaml:2: world: 'atlantis' is neither"));
  CHECK_THAT(ScenarioError("name: x\nworld: office\n"), Catch::Contains("missing key 'traversals'"));
}

TEST_CASE("an unknown scenario name lists the built-in ones", "[simulation][scenario][bad-input]") {
  try {
    LoadScenario("office-party");
    FAIL("no error");
  } catch (const FileError& e) {
    CHECK(std::string(e.what()).find("office-static, office-change, office-split, office-lighting") != std::string::npos);
  }
}

}  // namespace
}  // namespace catgraph
