// The dataset format every catgraph reader and writer of image sequences
// uses (docs/dataset-format.md): a folder with
//
//   images/NNNNNN.png   one image per frame
//   frames.csv          timestamp,image,traversal,changed[,changed_fraction]
//   odometry.csv        timestamp,x,y,theta   (the odometry frame, SE(2))
//   groundtruth.csv     timestamp,x,y,theta   (optional for real data)
//   meta.json           format version, scenario, seed, camera, changed regions,
//                       per-frame change flags, floor plan when simulated
//
// The simulator (`catgraph simulate`) and the image-sequence converter write
// it; the front end reads it. ReadDataset checks everything a consumer relies
// on — sorted timestamps, images that exist, every frame inside the odometry's
// time range, meta.json agreeing with frames.csv — and throws a FileError
// naming the file, the line and what was expected.
#ifndef CATGRAPH_BACKEND_IO_DATASET_H_
#define CATGRAPH_BACKEND_IO_DATASET_H_

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "backend/graph/pose2.h"

namespace catgraph {

inline constexpr int kDatasetFormatVersion = 1;

struct TimedPose2 {
  double timestamp_s = 0.0;
  Pose2 pose;
};

struct DatasetFrame {
  double timestamp_s = 0.0;
  std::string image;              // path relative to the dataset folder
  int traversal = 1;              // 1-based traversal id
  bool changed = false;           // the frame sees a changed region
  double changed_fraction = 0.0;  // fraction of its pixels that do; 0 when unknown
};

using Polygon2 = std::vector<Eigen::Vector2d>;

struct ChangedRegion {
  std::string name;
  std::string kind;  // "furniture", "lighting", ...
  Polygon2 polygon;  // world frame, metres
};

// A piece of furniture as simulated, for plots and ground-truth checks.
struct FurnitureFootprint {
  std::string name;
  Polygon2 polygon;
  double height_m = 0.0;
  std::vector<int> traversals;  // the traversals in which it stands
};

struct DatasetCamera {
  std::string model = "unknown";  // "cylindrical" for the simulator
  int width_px = 0, height_px = 0;
  double hfov_deg = 0.0, vfov_deg = 0.0;
  double height_m = 0.0;       // above the floor; 0 when unknown
  double frame_rate_hz = 0.0;  // nominal; 0 when unknown
};

struct DatasetMeta {
  int format_version = kDatasetFormatVersion;
  std::string scenario;           // scenario name or the source of converted data
  std::uint64_t seed = 0;
  bool synthetic_images = false;  // rendered by the simulator
  bool synthetic_odometry = false;
  bool synthetic_ground_truth = false;  // positions made up (converted real data)
  std::string note;                     // free text: provenance, caveats
  DatasetCamera camera;
  double odometry_rate_hz = 0.0;
  std::vector<ChangedRegion> changed_regions;
  std::vector<bool> frame_changed;  // one per frame; must agree with frames.csv
  // Floor plan when simulated: wall segments (x0, y0, x1, y1) and furniture.
  std::vector<Eigen::Vector4d> walls;
  std::vector<FurnitureFootprint> furniture;
};

struct Dataset {
  std::filesystem::path root;
  DatasetMeta meta;
  std::vector<DatasetFrame> frames;
  std::vector<TimedPose2> odometry;
  std::vector<TimedPose2> ground_truth;  // empty when the dataset has none

  bool HasGroundTruth() const { return !ground_truth.empty(); }
  std::filesystem::path ImagePath(std::size_t frame) const { return root / frames.at(frame).image; }
  // The traversal ids in order of first appearance.
  std::vector<int> Traversals() const;
};

// Reads and checks a dataset folder. Throws FileError.
Dataset ReadDataset(const std::filesystem::path& root);

// A `timestamp,x,y,theta` table (odometry.csv, groundtruth.csv): the header,
// then at least two rows with strictly increasing timestamps. With
// `comments`, lines starting with '#' are skipped (files of other tools;
// the dataset's own tables have none). Throws FileError naming the line.
std::vector<TimedPose2> ReadPoseTable(const std::filesystem::path& path, bool comments = false);

// Writes frames.csv, odometry.csv, groundtruth.csv (when not empty) and
// meta.json of `dataset` into dataset.root, each atomically. Images are the
// caller's. Throws std::invalid_argument when the tables are inconsistent
// (the same checks ReadDataset makes, except image existence).
void WriteDatasetTables(const Dataset& dataset);

// Every file of `dataset` that ReadDataset read or that its frames name: the
// tables, meta.json and the images.
std::vector<std::filesystem::path> DatasetFiles(const Dataset& dataset);

// The pose at time t, interpolated linearly between the two samples around it
// (heading along the shorter arc). Throws std::out_of_range outside the
// samples' time range; `poses` must be sorted by time.
Pose2 InterpolatePose(const std::vector<TimedPose2>& poses, double t);

// `poses` (odometry or ground truth) at every frame time of `dataset`, in
// frame order; empty when `poses` is.
std::vector<Pose2> PosesAtFrames(const Dataset& dataset, const std::vector<TimedPose2>& poses);

// True when p lies inside the polygon (even-odd rule; boundary counts as
// inside up to rounding).
bool PointInPolygon(const Polygon2& polygon, const Eigen::Vector2d& p);

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_IO_DATASET_H_
