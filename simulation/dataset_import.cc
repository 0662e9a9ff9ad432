#include "simulation/dataset_import.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <charconv>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "backend/graph/name_table.h"
#include "backend/io/atomic_file.h"
#include "backend/io/dataset.h"
#include "backend/io/file_error.h"
#include "backend/io/image_file.h"
#include "backend/io/internal/text_line.h"

namespace catgraph {
namespace {

constexpr std::size_t kMaxFrames = 1000000;
constexpr std::size_t kMaxLineBytes = 4096;

// A frame of the recording: its time and the image file it comes from.
struct SourceFrame {
  double timestamp_s = 0.0;
  std::filesystem::path image;
};

// A camera pose in 3D (optical convention), timed.
struct TimedPose3 {
  double timestamp_s = 0.0;
  Eigen::Vector3d translation;
  Eigen::Matrix3d rotation;
};

bool IsImage(const std::filesystem::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".pgm" || ext == ".ppm" || ext == ".pnm" ||
         ext == ".bmp";
}

std::vector<std::filesystem::path> ImagesIn(const std::filesystem::path& dir) {
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) throw FileError(dir.string(), 0, "no such folder; expected images");
  std::vector<std::filesystem::path> images;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    if (e.is_regular_file() && IsImage(e.path())) images.push_back(e.path());
    if (images.size() > kMaxFrames) throw FileError(dir.string(), 0, "holds more than a million images");
  }
  if (images.empty()) throw FileError(dir.string(), 0, "holds no images (.png, .jpg, .pgm, .ppm, .bmp)");
  std::sort(images.begin(), images.end());
  return images;
}

// Calls `row` with each content line of `path` (blank lines and lines
// starting with '#' skipped), tokenised by `split`.
template <typename Split, typename Row>
void ForEachLine(const std::filesystem::path& path, std::string_view expected, Split split, Row row) {
  std::ifstream in = OpenForReading(path, expected);
  std::string text;
  int number = 0;
  const std::string name = path.string();
  while (ReadBoundedLine(in, text, kMaxLineBytes, name, number, expected)) {
    ++number;
    std::string_view trimmed = text;
    const std::size_t first = trimmed.find_first_not_of(kWhitespace);
    trimmed = first == std::string_view::npos ? std::string_view() : trimmed.substr(first);
    trimmed = trimmed.substr(0, trimmed.find_last_not_of(kWhitespace) + 1);
    if (trimmed.empty() || trimmed.front() == '#') continue;
    row(Line(name, number, split(trimmed), std::string_view(expected)));
  }
}

double Timestamp(const Line& line, std::size_t index) {
  const double t = line.Number(index, "the timestamp");
  if (t < 0.0) line.Fail("the timestamp is negative");
  return t;
}

void RequireIncreasing(const std::vector<double>& times, const std::filesystem::path& path) {
  for (std::size_t i = 1; i < times.size(); ++i) {
    if (!(times[i] > times[i - 1])) {
      throw FileError(path.string(), 0, "timestamps are not strictly increasing (entry " + std::to_string(i + 1) + ")");
    }
  }
}

// `timestamp,x,y,theta` with that header (the dataset's own odometry.csv),
// comment lines allowed; timestamps not negative, as every input's.
std::vector<TimedPose2> ReadPose2Csv(const std::filesystem::path& path) {
  std::vector<TimedPose2> poses = ReadPoseTable(path, /*comments=*/true);
  if (poses.front().timestamp_s < 0.0) throw FileError(path.string(), 0, "the first timestamp is negative");
  return poses;
}

// One number per line.
std::vector<double> ReadTimes(const std::filesystem::path& path) {
  std::vector<double> times;
  ForEachLine(path, "a times file (one timestamp per line)", Tokenize, [&](const Line& line) {
    if (line.size() != 1) line.Fail("expected one timestamp, found " + std::to_string(line.size()) + " fields");
    times.push_back(Timestamp(line, 0));
  });
  RequireIncreasing(times, path);
  return times;
}

// KITTI: 12 numbers per line, the row-major 3 x 4 camera-to-world matrix.
std::vector<TimedPose3> ReadKittiPoses(const std::filesystem::path& path, const std::vector<double>& times) {
  std::vector<TimedPose3> poses;
  ForEachLine(path, "a KITTI poses file (12 numbers per line)", Tokenize, [&](const Line& line) {
    if (line.size() != 12) line.Fail("expected 12 numbers (a 3 x 4 matrix), found " + std::to_string(line.size()));
    TimedPose3 p;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) p.rotation(r, c) = line.Number(static_cast<std::size_t>(4 * r + c), "a rotation entry");
      p.translation(r) = line.Number(static_cast<std::size_t>(4 * r + 3), "a translation entry");
    }
    if (!((p.rotation.transpose() * p.rotation - Eigen::Matrix3d::Identity()).norm() < 1e-3)) {
      line.Fail("the 3 x 3 block is not a rotation");
    }
    if (poses.size() >= times.size()) line.Fail("more poses than times.txt has timestamps");
    p.timestamp_s = times[poses.size()];
    poses.push_back(p);
  });
  if (poses.size() != times.size()) {
    throw FileError(path.string(), 0, "holds " + std::to_string(poses.size()) + " poses for " +
                                          std::to_string(times.size()) + " timestamps in times.txt");
  }
  return poses;
}

// TUM: "timestamp tx ty tz qx qy qz qw".
std::vector<TimedPose3> ReadTumPoses(const std::filesystem::path& path) {
  std::vector<TimedPose3> poses;
  ForEachLine(path, "a TUM trajectory (timestamp tx ty tz qx qy qz qw)", Tokenize, [&](const Line& line) {
    if (line.size() != 8) line.Fail("expected 8 numbers (timestamp tx ty tz qx qy qz qw), found " + std::to_string(line.size()));
    TimedPose3 p;
    p.timestamp_s = Timestamp(line, 0);
    p.translation = {line.Number(1, "tx"), line.Number(2, "ty"), line.Number(3, "tz")};
    const Eigen::Quaterniond q(line.Number(7, "qw"), line.Number(4, "qx"), line.Number(5, "qy"), line.Number(6, "qz"));
    if (!(std::abs(q.norm() - 1.0) < 1e-2)) line.Fail("the quaternion is not of unit length");
    p.rotation = q.normalized().toRotationMatrix();
    poses.push_back(p);
  });
  std::vector<double> times;
  for (const auto& p : poses) times.push_back(p.timestamp_s);
  RequireIncreasing(times, path);
  return poses;
}

// TUM's rgb.txt: "timestamp filename".
std::vector<SourceFrame> ReadTumFrames(const std::filesystem::path& root) {
  const std::filesystem::path list = root / "rgb.txt";
  std::vector<SourceFrame> frames;
  ForEachLine(list, "a TUM image list (timestamp filename)", Tokenize, [&](const Line& line) {
    if (line.size() != 2) line.Fail("expected 'timestamp filename', found " + std::to_string(line.size()) + " fields");
    const std::filesystem::path image = root / std::string(line.token(1));
    std::error_code ec;  // a name too long for the file system is no image either
    if (!std::filesystem::is_regular_file(image, ec)) line.Fail("no image '" + image.string() + "'");
    if (!IsImage(image)) line.Fail("'" + image.string() + "' is not a .png, .jpg, .pgm, .ppm or .bmp image");
    frames.push_back({Timestamp(line, 0), image});
    if (frames.size() > kMaxFrames) line.Fail("more than a million frames");
  });
  std::vector<double> times;
  for (const auto& f : frames) times.push_back(f.timestamp_s);
  RequireIncreasing(times, list);
  return frames;
}

// The camera's 3D poses on the ground plane: the plane normal to the mean of
// the cameras' y axes (down in the optical convention), the first frame at
// the origin facing +x (its optical axis projected).
std::vector<TimedPose2> OntoGroundPlane(const std::vector<TimedPose3>& poses, const std::filesystem::path& file) {
  if (poses.size() < 2) throw FileError(file.string(), 0, "fewer than two poses");
  Eigen::Vector3d down = Eigen::Vector3d::Zero();
  for (const auto& p : poses) down += p.rotation.col(1);
  if (!(down.norm() > 0.5 * static_cast<double>(poses.size()))) {
    throw FileError(file.string(), 0,
                    "the camera's y axis (down, optical convention) turns through more than a ground "
                    "robot's camera does; expected a camera looking roughly level");
  }
  const Eigen::Vector3d up = -down.normalized();
  auto on_plane = [&](const Eigen::Vector3d& v) { return Eigen::Vector3d(v - v.dot(up) * up); };
  Eigen::Vector3d e1 = on_plane(poses.front().rotation.col(2));
  if (!(e1.norm() > 1e-3)) throw FileError(file.string(), 0, "the first camera looks straight up or down");
  e1.normalize();
  const Eigen::Vector3d e2 = up.cross(e1);
  const Eigen::Vector3d origin = poses.front().translation;
  std::vector<TimedPose2> out;
  out.reserve(poses.size());
  for (const auto& p : poses) {
    const Eigen::Vector3d d = p.translation - origin, f = p.rotation.col(2);
    out.push_back({p.timestamp_s, Pose2(d.dot(e1), d.dot(e2), std::atan2(f.dot(e2), f.dot(e1)))});
  }
  return out;
}

// The frames of the folder layout: sorted images, timestamps from the times
// file or the file names.
// The frames of the folder layout: the images with the times file's
// timestamps in file-name order, or each image's file name as its timestamp
// (then sorted by it: names of different lengths do not sort by time).
std::vector<SourceFrame> FolderFrames(const std::filesystem::path& dir, const std::filesystem::path& times_file) {
  const std::vector<std::filesystem::path> images = ImagesIn(dir);
  std::vector<SourceFrame> frames;
  if (!times_file.empty()) {
    const std::vector<double> times = ReadTimes(times_file);
    if (times.size() != images.size()) {
      throw FileError(times_file.string(), 0, "holds " + std::to_string(times.size()) + " timestamps for " +
                                                  std::to_string(images.size()) + " images in " + dir.string());
    }
    for (std::size_t i = 0; i < images.size(); ++i) frames.push_back({times[i], images[i]});
    return frames;
  }
  for (const auto& image : images) {
    const std::string stem = image.stem().string();
    double t = 0.0;
    const auto [end, ec] = std::from_chars(stem.data(), stem.data() + stem.size(), t);
    if (ec != std::errc() || end != stem.data() + stem.size() || !std::isfinite(t) || t < 0.0) {
      throw FileError(image.string(), 0,
                      "the file name is not a timestamp; name the images by time (seconds, or nanoseconds) "
                      "or give a times file with one timestamp per image");
    }
    frames.push_back({t > 1e12 ? t * 1e-9 : t, image});
  }
  std::sort(frames.begin(), frames.end(),
            [](const SourceFrame& a, const SourceFrame& b) { return a.timestamp_s < b.timestamp_s; });
  for (std::size_t i = 1; i < frames.size(); ++i) {
    if (!(frames[i].timestamp_s > frames[i - 1].timestamp_s)) {
      throw FileError(frames[i].image.string(), 0, "has the same timestamp as " + frames[i - 1].image.string());
    }
  }
  return frames;
}

constexpr NameTable<ImportLayout, 3> kImportLayoutNames = {{
    {ImportLayout::kFolder, "folder"},
    {ImportLayout::kKitti, "kitti"},
    {ImportLayout::kTum, "tum"},
}};

void ValidateOptions(const ImportOptions& o) {
  if (!(o.traversal_gap_s > 0.0 && std::isfinite(o.traversal_gap_s))) {
    throw std::invalid_argument("traversal_gap_s: expected a finite number of seconds > 0");
  }
  if (!(o.track_m > 0.0 && std::isfinite(o.track_m))) throw std::invalid_argument("track_m: expected > 0");
  Validate(o.odometry_noise);
}

}  // namespace

std::string_view ToString(ImportLayout layout) { return NameOf(kImportLayoutNames, layout); }

std::optional<ImportLayout> ImportLayoutFromString(std::string_view text) {
  return ValueOf(kImportLayoutNames, text);
}

std::vector<std::string> ImportLayoutNames() { return NamesOf(kImportLayoutNames); }

ImportSummary ImportDataset(ImportLayout layout, const std::filesystem::path& source,
                            const std::filesystem::path& output, const ImportOptions& options) {
  ValidateOptions(options);
  std::vector<SourceFrame> frames;
  std::vector<TimedPose2> odometry, truth;
  std::string what;
  switch (layout) {
    case ImportLayout::kFolder:
      if (options.odometry.empty() && options.poses.empty()) {
        throw std::invalid_argument("the folder layout needs an odometry CSV, a pose CSV or both");
      }
      frames = FolderFrames(source, options.times);
      if (!options.odometry.empty()) odometry = ReadPose2Csv(options.odometry);
      if (!options.poses.empty()) truth = ReadPose2Csv(options.poses);
      what = "an image folder";
      break;
    case ImportLayout::kKitti: {
      if (options.poses.empty()) {
        throw std::invalid_argument("the KITTI layout needs its poses file (poses/NN.txt of the odometry set)");
      }
      std::filesystem::path images = source / "image_0";
      std::error_code ec;
      if (!std::filesystem::is_directory(images, ec)) images = source / "image_2";
      const std::vector<double> times = ReadTimes(source / "times.txt");
      const std::vector<std::filesystem::path> files = ImagesIn(images);
      if (files.size() != times.size()) {
        throw FileError((source / "times.txt").string(), 0, "holds " + std::to_string(times.size()) +
                                                               " timestamps for " + std::to_string(files.size()) +
                                                               " images in " + images.string());
      }
      for (std::size_t i = 0; i < files.size(); ++i) frames.push_back({times[i], files[i]});
      truth = OntoGroundPlane(ReadKittiPoses(options.poses, times), options.poses);
      what = "the KITTI odometry layout";
      break;
    }
    case ImportLayout::kTum: {
      frames = ReadTumFrames(source);
      const std::filesystem::path truth_file = source / "groundtruth.txt", odometry_file = source / "odometry.txt";
      truth = OntoGroundPlane(ReadTumPoses(truth_file), truth_file);
      std::error_code ec;
      if (std::filesystem::exists(odometry_file, ec)) odometry = OntoGroundPlane(ReadTumPoses(odometry_file), odometry_file);
      what = "the TUM RGB-D layout";
      break;
    }
  }
  ImportSummary summary;
  summary.ground_truth = !truth.empty();
  if (odometry.empty()) {
    odometry = WheelOdometryAlong(truth, options.track_m, options.odometry_noise, options.seed);
    summary.synthetic_odometry = true;
  }
  // Every reader above returns at least two poses.

  // Frames inside the odometry's and the poses' time ranges.
  auto inside = [](const std::vector<TimedPose2>& poses, double t) {
    return poses.empty() || (t >= poses.front().timestamp_s && t <= poses.back().timestamp_s);
  };
  std::vector<SourceFrame> kept;
  for (const SourceFrame& f : frames) {
    if (inside(odometry, f.timestamp_s) && inside(truth, f.timestamp_s)) kept.push_back(f);
  }
  summary.left_out = frames.size() - kept.size();
  if (kept.empty()) {
    throw FileError(source.string(), 0,
                    "no frame lies inside the time range of the odometry and the poses; do they share the images' clock?");
  }

  CreateDirectories(output / "images");
  Dataset d;
  d.root = output;
  cv::Size size;
  int traversal = 1;
  for (std::size_t i = 0; i < kept.size(); ++i) {
    if (i > 0 && kept[i].timestamp_s - kept[i - 1].timestamp_s > options.traversal_gap_s) ++traversal;
    if (size.empty()) size = ReadImage(kept[i].image).size();
    std::string ext = kept[i].image.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    char name[40];
    std::snprintf(name, sizeof name, "images/%06zu%s", i, ext.c_str());
    std::error_code ec;
    std::filesystem::copy_file(kept[i].image, output / name, std::filesystem::copy_options::overwrite_existing, ec);
    if (ec) throw FileError(kept[i].image.string(), 0, "cannot be copied: " + ec.message());
    d.frames.push_back({kept[i].timestamp_s, name, traversal, false, 0.0});
    d.meta.frame_changed.push_back(false);
    if (options.on_progress) options.on_progress(i + 1, kept.size());
  }
  // The odometry and poses over the frames' time range (one sample either side).
  auto clip = [&](const std::vector<TimedPose2>& poses) {
    std::vector<TimedPose2> out;
    const double first = d.frames.front().timestamp_s, last = d.frames.back().timestamp_s;
    for (std::size_t i = 0; i < poses.size(); ++i) {
      const bool before = i + 1 < poses.size() && poses[i + 1].timestamp_s <= first;
      const bool after = i > 0 && poses[i - 1].timestamp_s >= last;
      if (!before && !after) out.push_back(poses[i]);
    }
    return out;
  };
  d.odometry = clip(odometry);
  d.ground_truth = clip(truth);
  if (d.odometry.size() < 2) d.odometry = {odometry.front(), odometry.back()};
  if (!truth.empty() && d.ground_truth.size() < 2) d.ground_truth = {truth.front(), truth.back()};

  DatasetMeta& m = d.meta;
  m.scenario = "import:" + std::string(ToString(layout)) + ":" +
               std::filesystem::absolute(source).lexically_normal().filename().string();
  m.seed = options.seed;
  m.synthetic_odometry = summary.synthetic_odometry;
  std::string note = "imported from " + source.string() + " (" + what + ") by catgraph import; real images";
  if (summary.synthetic_odometry) {
    note += "; odometry made from the poses by the simulator's wheel-odometry model (seed " +
            std::to_string(options.seed) + ")";
  }
  if (layout != ImportLayout::kFolder) note += "; 3D camera poses projected onto the ground plane";
  if (summary.left_out > 0) {
    note += "; " + std::to_string(summary.left_out) + " frames outside the odometry's or the poses' time range left out";
  }
  note += "; changed flags unknown (0)";
  m.note = note;
  m.camera.width_px = size.width;
  m.camera.height_px = size.height;
  const double span = d.frames.back().timestamp_s - d.frames.front().timestamp_s;
  m.camera.frame_rate_hz = d.frames.size() > 1 && span > 0.0 ? static_cast<double>(d.frames.size() - 1) / span : 0.0;
  const double odo_span = d.odometry.back().timestamp_s - d.odometry.front().timestamp_s;
  m.odometry_rate_hz = odo_span > 0.0 ? static_cast<double>(d.odometry.size() - 1) / odo_span : 0.0;
  WriteDatasetTables(d);
  summary.frames = d.frames.size();
  summary.traversals = traversal;
  return summary;
}

}  // namespace catgraph
