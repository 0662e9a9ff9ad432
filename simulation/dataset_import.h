// Bring your own data: turns a recorded image sequence into the project's
// dataset format (docs/dataset-format.md) so that `localize` and `map` run
// on it. Three layouts (docs/import.md):
//
//   folder  a folder of images (sorted by file name) with their timestamps
//           (a times file, one per image, or numeric file names), and an
//           odometry and/or a pose CSV (`timestamp,x,y,theta`, SE(2));
//   kitti   the KITTI odometry layout: image_0/ (or image_2/), times.txt and
//           a poses file (poses/NN.txt, 3 x 4 camera-to-world matrices);
//   tum     the TUM RGB-D layout: rgb.txt and groundtruth.txt
//           (timestamp tx ty tz qx qy qz qw), odometry.txt in that format
//           when the recording has wheel odometry.
//
// Camera poses in 3D (KITTI, TUM) are in the optical convention (z forward,
// x right, y down); they are brought onto the ground plane, the plane normal
// to the camera's mean y axis, with the first frame at the origin facing +x.
// Where a recording has poses but no odometry, the odometry is made from the
// poses by the simulator's wheel-odometry model (robot.h's
// WheelOdometryAlong, seeded) and meta.json says so (synthetic_odometry). Frames outside the
// time range of the odometry or the poses are left out and counted. A gap
// in the frames' timestamps longer than `traversal_gap_s` starts a new
// traversal. Images are copied as they are (PNG, JPEG, PNM, BMP).
//
// Every problem in an input file is a FileError naming the file and line.
#ifndef CATGRAPH_SIMULATION_DATASET_IMPORT_H_
#define CATGRAPH_SIMULATION_DATASET_IMPORT_H_

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "simulation/robot.h"

namespace catgraph {

enum class ImportLayout { kFolder, kKitti, kTum };
std::string_view ToString(ImportLayout layout);
std::optional<ImportLayout> ImportLayoutFromString(std::string_view text);  // "folder", "kitti", "tum"
std::vector<std::string> ImportLayoutNames();  // every spelling ImportLayoutFromString accepts

struct ImportOptions {
  // folder: the image timestamps, one per line in the images' name order;
  // empty: each image's file name (without extension) is its timestamp, in
  // seconds, or in nanoseconds when over 10^12.
  std::filesystem::path times;
  // folder: `timestamp,x,y,theta` files (a header line, then rows); at least
  // one of the two. kitti: `poses` is the poses file (required; KITTI's
  // test sequences have none).
  std::filesystem::path odometry, poses;
  double traversal_gap_s = 5.0;  // > 0
  std::uint64_t seed = 1;        // the made-up odometry's noise
  OdometryOptions odometry_noise;
  double track_m = RobotOptions().track_m;  // the wheel-odometry model's track; > 0
  std::function<void(std::size_t done, std::size_t total)> on_progress;
};

struct ImportSummary {
  std::size_t frames = 0;
  std::size_t left_out = 0;  // frames outside the odometry's or the poses' time range
  int traversals = 0;
  bool synthetic_odometry = false;
  bool ground_truth = false;
};

// Reads the recording at `source` in `layout` and writes the dataset into
// `output` (a folder the caller prepared). Throws FileError for a problem in
// an input (naming the file, and the line where there is one),
// std::invalid_argument for options out of range or inputs missing for the
// layout.
ImportSummary ImportDataset(ImportLayout layout, const std::filesystem::path& source,
                            const std::filesystem::path& output, const ImportOptions& options);

}  // namespace catgraph

#endif  // CATGRAPH_SIMULATION_DATASET_IMPORT_H_
