// Makes a dataset (docs/dataset-format.md) from a scenario: drives the robot
// along the traversals' routes, renders a camera frame at the camera's frame
// rate, records wheel odometry and ground truth, and labels every frame with
// whether it sees a changed region.
//
// Deterministic: the same scenario and seed give byte-identical files. The
// seed drives the odometry noise and the image noise; the world's look comes
// from the floor plan's texture_seed, so two seeds show the same building.
#ifndef CATGRAPH_SIMULATION_OFFICE_SIMULATOR_H_
#define CATGRAPH_SIMULATION_OFFICE_SIMULATOR_H_

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <vector>

#include "simulation/office_world.h"
#include "simulation/robot.h"
#include "simulation/scenario.h"

namespace catgraph {

struct SimulationOptions {
  std::optional<std::uint64_t> seed;  // overrides the scenario's seed
  std::size_t max_frames = 0;         // 0: every frame of every traversal
  int threads = 0;                    // rendering threads; 0: the machine's cores
  // Called from the calling thread after each frame is written.
  std::function<void(std::size_t done, std::size_t total)> on_progress;
};

// A frame to render: when, which traversal, and where the camera truly is.
struct PlannedFrame {
  double timestamp_s = 0.0;
  int traversal = 1;
  Pose2 T_world_camera;
};

// The frames at the camera's rate over the whole run (at most max_frames;
// 0 = all).
std::vector<PlannedFrame> PlanFrames(const RobotRun& run, double frame_rate_hz,
                                     std::size_t max_frames);

// The world of a scenario, textures built.
OfficeWorld MakeWorld(const Scenario& scenario);

// The robot's run for a scenario and seed.
RobotRun DriveScenario(const Scenario& scenario, std::uint64_t seed);

// The seed of frame `index`'s sensor noise.
std::uint64_t FrameNoiseSeed(std::uint64_t seed, std::size_t index);

struct SimulationSummary {
  std::size_t frames = 0;
  std::vector<std::size_t> frames_per_traversal;
  std::vector<double> distance_m;  // driven per traversal
  std::size_t changed_frames = 0;
  double duration_s = 0.0;         // simulated time
};

// Writes the dataset into `directory` (created if needed; files of the same
// name are replaced, nothing is deleted: give a new folder, or stage one with
// OutputDirectory as `catgraph simulate` does). Every file is written
// atomically. Throws std::invalid_argument, std::runtime_error or FileError.
SimulationSummary SimulateDataset(const Scenario& scenario, const std::filesystem::path& directory,
                                  const SimulationOptions& options);

}  // namespace catgraph

#endif  // CATGRAPH_SIMULATION_OFFICE_SIMULATOR_H_
