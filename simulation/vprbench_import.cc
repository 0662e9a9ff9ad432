#include "simulation/vprbench_import.h"

#include <algorithm>
#include <cctype>
#include <tuple>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "backend/io/atomic_file.h"
#include "backend/io/dataset.h"
#include "backend/io/file_error.h"
#include "backend/io/image_file.h"

namespace catgraph {
namespace {

constexpr std::size_t kMaxImages = 1000000;

std::vector<std::filesystem::path> ImagesIn(const std::filesystem::path& dir) {
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) {
    throw FileError(dir.string(), 0, "no such directory; expected a folder of images (VPR-Bench layout: ref/, query/)");
  }
  std::vector<std::filesystem::path> images;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    std::string ext = e.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (e.is_regular_file() && (ext == ".jpg" || ext == ".jpeg" || ext == ".png")) images.push_back(e.path());
    if (images.size() > kMaxImages) throw FileError(dir.string(), 0, "holds more than a million images");
  }
  std::sort(images.begin(), images.end());
  if (images.empty()) throw FileError(dir.string(), 0, "holds no .jpg or .png images");
  return images;
}

// The time at which the robot, driving traversal `id`, passes x = x_m.
double CrossingTime(const RobotRun& run, int id, double x_m) {
  for (std::size_t i = 1; i < run.truth.size(); ++i) {
    if (run.traversal[i] != id) continue;
    const double x0 = run.truth[i - 1].pose.x(), x1 = run.truth[i].pose.x();
    if (x0 < x_m && x1 >= x_m) {
      const double a = (x_m - x0) / (x1 - x0);
      return run.truth[i - 1].timestamp_s + a * (run.truth[i].timestamp_s - run.truth[i - 1].timestamp_s);
    }
  }
  throw std::runtime_error("the made-up drive never reached x = " + std::to_string(x_m));
}

}  // namespace

VprBenchImportSummary ImportVprBench(const std::filesystem::path& source,
                                     const std::filesystem::path& output,
                                     const VprBenchImportOptions& options) {
  if (!(options.spacing_m > 0.0 && options.spacing_m <= 100.0)) {
    throw std::invalid_argument("spacing_m: expected a distance in (0, 100] m");
  }
  const std::vector<std::filesystem::path> reference = ImagesIn(source / "ref");
  const std::vector<std::filesystem::path> query = ImagesIn(source / "query");

  // Out along y = 0, back on a parallel lane 2 m away, out again.
  const double length = static_cast<double>(std::max(reference.size(), query.size()) - 1) * options.spacing_m;
  const double lead = 0.3 + options.robot.lookahead_m;
  std::vector<TraversalPlan> plans(3);
  plans[0] = {1, options.speed_m_s, 0.0, {{-lead, 0.0}, {length + lead, 0.0}}};
  plans[1] = {2, options.speed_m_s, 0.0,
              {{length + lead, 0.0}, {length + lead + 1.5, 0.0}, {length + lead + 1.5, 3.0},
               {-lead - 1.5, 3.0}, {-lead - 1.5, 0.0}, {-lead, 0.0}}};
  plans[2] = {3, options.speed_m_s, 0.0, {{-lead, 0.0}, {length + lead, 0.0}}};
  const RobotRun run = DriveRoutes(plans, options.robot, options.odometry, options.seed);

  CreateDirectories(output / "images");
  Dataset d;
  d.root = output;
  const std::size_t total = reference.size() + query.size();
  cv::Size size;
  for (const auto& [images, drive_id, traversal] :
       {std::tuple{&reference, 1, 1}, std::tuple{&query, 3, 2}}) {
    for (std::size_t i = 0; i < images->size(); ++i) {
      const std::filesystem::path& from = (*images)[i];
      const cv::Mat image = ReadImage(from);
      if (size.empty()) size = image.size();
      char name[32];
      std::snprintf(name, sizeof name, "images/%06zu.png", d.frames.size());
      std::vector<std::uint8_t> png;
      cv::imencode(".png", image, png);
      WriteBytesAtomically(output / name, png);
      d.frames.push_back({CrossingTime(run, drive_id, static_cast<double>(i) * options.spacing_m), name,
                          traversal, false, 0.0});
      d.meta.frame_changed.push_back(false);
      if (options.on_progress) options.on_progress(d.frames.size(), total);
    }
  }
  const double last = d.frames.back().timestamp_s;
  for (const auto& o : run.odometry) {
    d.odometry.push_back(o);
    if (o.timestamp_s >= last) break;
  }
  std::vector<double> times;
  for (const auto& o : d.odometry) times.push_back(o.timestamp_s);
  for (const auto& f : d.frames) times.push_back(f.timestamp_s);
  d.ground_truth = TruthAt(run, std::move(times));
  DatasetMeta& m = d.meta;
  m.scenario = "vprbench:" + std::filesystem::absolute(source).lexically_normal().filename().string();
  m.seed = options.seed;
  m.synthetic_odometry = true;
  m.synthetic_ground_truth = true;
  char note[256];
  std::snprintf(note, sizeof note,
                "converted from %s by catgraph convert-vprbench; real images, made-up metric route: "
                "frame i of each traversal at x = %g * i m, odometry simulated; changed flags unknown (0)",
                source.string().c_str(), options.spacing_m);
  m.note = note;
  m.camera.width_px = size.width;
  m.camera.height_px = size.height;
  m.camera.frame_rate_hz = options.speed_m_s / options.spacing_m;
  m.odometry_rate_hz = options.odometry.rate_hz;
  WriteDatasetTables(d);
  return {reference.size(), query.size()};
}

}  // namespace catgraph
