// Scenarios: everything the simulator needs to make one dataset, in one
// human-readable YAML file (docs/simulation.md): the world (a built-in floor
// plan by name, a world file, or inline), furniture and in which traversals it
// stands, lighting regions, the regions that change between traversals, the
// camera, the robot, its odometry's noise, and each traversal's route.
//
// The built-in scenarios (office-static, office-change, office-split,
// office-lighting) and the office world are the YAML files of
// simulation/scenarios/, compiled into the library; `catgraph simulate
// --print-scenario NAME` prints one to copy and edit.
//
// Every problem in a file — a YAML syntax error, an unknown key, a value of
// the wrong type or range, a route through a wall — is a FileError naming the
// file and the line.
#ifndef CATGRAPH_SIMULATION_SCENARIO_H_
#define CATGRAPH_SIMULATION_SCENARIO_H_

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "backend/io/dataset.h"
#include "simulation/office_world.h"
#include "simulation/robot.h"

namespace catgraph {

struct Scenario {
  std::string name;
  std::string description;
  std::uint64_t seed = 1;  // noise of odometry and images; the world's look has its own seed
  FloorPlan floor_plan;
  std::vector<Furniture> furniture;
  std::vector<LightingRegion> lighting;
  std::vector<ChangedRegion> changed_regions;
  CameraOptions camera;
  RobotOptions robot;
  OdometryOptions odometry;
  std::vector<TraversalPlan> traversals;
  // A frame "sees a changed region" when at least this fraction of its
  // pixels land in one; (0, 1].
  double changed_pixel_fraction = 0.1;
};

struct EmbeddedFile {
  std::string_view name;  // file name without .yaml
  std::string_view text;
};
// The files of simulation/scenarios/, compiled in.
const std::vector<EmbeddedFile>& EmbeddedScenarioFiles();

// The names of the built-in scenarios (not the worlds).
std::vector<std::string> BuiltInScenarioNames();
// The YAML text of a built-in scenario or world; throws std::invalid_argument
// listing the names when there is none of that name.
std::string_view BuiltInScenarioText(std::string_view name);

// A built-in scenario by name, else a scenario file. Throws FileError.
Scenario LoadScenario(const std::string& name_or_path);

// Parses scenario YAML. `source` names it in errors; a world file is looked
// up relative to `base_dir`. Throws FileError.
Scenario ParseScenario(std::string_view yaml, const std::string& source,
                       const std::filesystem::path& base_dir);

}  // namespace catgraph

#endif  // CATGRAPH_SIMULATION_SCENARIO_H_
