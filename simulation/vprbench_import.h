// Turns a VPR-Bench-style image set — a reference and a query traversal of
// the same route, index-aligned, without odometry or metric ground truth —
// into the project's dataset format (docs/dataset-format.md), so that the
// front end runs on real images.
//
// What is made up, and said so in meta.json (synthetic_odometry,
// synthetic_ground_truth): frame i of either traversal is placed i ·
// spacing_m along a straight route; the robot model of robot.h drives it (and
// back to the start between the traversals, without frames) and its wheel
// odometry, with the simulator's default noise, becomes odometry.csv. The
// ground truth is that made-up route, so "frame i of the query matches frame
// i of the reference" (the set's own ground truth) holds by construction.
// Nothing from the source is changed but the image encoding (PNG).
#ifndef CATGRAPH_SIMULATION_VPRBENCH_IMPORT_H_
#define CATGRAPH_SIMULATION_VPRBENCH_IMPORT_H_

#include <cstdint>
#include <filesystem>
#include <functional>

#include "simulation/robot.h"

namespace catgraph {

struct VprBenchImportOptions {
  double spacing_m = 0.5;         // made-up distance between frames; > 0
  double speed_m_s = 0.4;         // cruise speed of the made-up drive; >= robot.min_speed_m_s
  std::uint64_t seed = 1;         // odometry noise
  RobotOptions robot;
  OdometryOptions odometry;
  std::function<void(std::size_t done, std::size_t total)> on_progress;
};

struct VprBenchImportSummary {
  std::size_t reference_frames = 0, query_frames = 0;
};

// Reads `source`/ref/ and `source`/query/ (images sorted by file name) and
// writes the dataset into `output`. Throws FileError on a missing folder or
// an unreadable image.
VprBenchImportSummary ImportVprBench(const std::filesystem::path& source,
                                     const std::filesystem::path& output,
                                     const VprBenchImportOptions& options);

}  // namespace catgraph

#endif  // CATGRAPH_SIMULATION_VPRBENCH_IMPORT_H_
