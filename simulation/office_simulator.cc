#include "simulation/office_simulator.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <exception>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>

#include <opencv2/imgcodecs.hpp>

#include "backend/io/atomic_file.h"
#include "backend/io/file_error.h"
#include "simulation/hashing.h"

namespace catgraph {
namespace {

// Clearance the driven path keeps from walls and furniture: the Pioneer's
// half-width. The routes themselves keep more (scenario.cc).
constexpr double kBodyRadiusM = 0.2;

std::string ImageName(std::size_t index) {
  char name[32];
  std::snprintf(name, sizeof name, "images/%06zu.png", index);
  return name;
}

}  // namespace

std::uint64_t FrameNoiseSeed(std::uint64_t seed, std::size_t index) {
  return SplitMix64(SplitMix64(seed) ^ (0x5bd1e995ULL * (index + 1)));
}

OfficeWorld MakeWorld(const Scenario& s) {
  std::vector<int> ids;
  for (const auto& t : s.traversals) ids.push_back(t.id);
  return OfficeWorld(s.floor_plan, s.furniture, s.lighting, s.camera, ids);
}

RobotRun DriveScenario(const Scenario& s, std::uint64_t seed) {
  RobotRun run = DriveRoutes(s.traversals, s.robot, s.odometry, SplitMix64(seed));
  for (std::size_t i = 0; i < run.truth.size(); ++i) {
    const Pose2& p = run.truth[i].pose;
    if (!IsFreeSpace(s.floor_plan, s.furniture, p.translation(), run.traversal[i], kBodyRadiusM)) {
      std::ostringstream message;
      message.precision(3);
      message << "scenario " << s.name << ", traversal " << run.traversal[i] << ": at t = "
              << run.truth[i].timestamp_s << " s the robot comes within " << kBodyRadiusM
              << " m of a wall or furniture at (" << p.x() << ", " << p.y()
              << "); move the route away or round its corner";
      throw std::runtime_error(message.str());
    }
  }
  return run;
}

std::vector<PlannedFrame> PlanFrames(const RobotRun& run, double frame_rate_hz,
                                     std::size_t max_frames) {
  if (!(frame_rate_hz > 0.0)) throw std::invalid_argument("frame_rate_hz: expected > 0");
  std::vector<PlannedFrame> frames;
  const double end = run.truth.back().timestamp_s;
  for (std::size_t k = 0; max_frames == 0 || k < max_frames; ++k) {
    const double t = static_cast<double>(k) / frame_rate_hz;
    if (t > end) break;
    const auto it = std::lower_bound(run.truth.begin(), run.truth.end(), t,
                                     [](const TimedPose2& p, double time) { return p.timestamp_s < time; });
    const auto index = static_cast<std::size_t>(it - run.truth.begin());
    frames.push_back({t, run.traversal[index], InterpolatePose(run.truth, t)});
  }
  return frames;
}

SimulationSummary SimulateDataset(const Scenario& scenario, const std::filesystem::path& directory,
                                  const SimulationOptions& options) {
  const std::uint64_t seed = options.seed.value_or(scenario.seed);
  const RobotRun run = DriveScenario(scenario, seed);
  const std::vector<PlannedFrame> planned =
      PlanFrames(run, scenario.camera.frame_rate_hz, options.max_frames);
  const OfficeWorld world = MakeWorld(scenario);

  CreateDirectories(directory / "images");

  // Render and write the images on several threads; frames are independent.
  std::vector<double> changed_fraction(planned.size(), 0.0);
  std::atomic<std::size_t> next{0}, done{0};
  std::atomic<bool> failed{false};
  std::exception_ptr error;
  std::mutex mutex;
  std::condition_variable progressed;
  auto work = [&] {
    try {
      for (std::size_t i = next++; i < planned.size() && !failed; i = next++) {
        RenderDetail detail;
        const cv::Mat3b image = world.Render(planned[i].T_world_camera, planned[i].traversal,
                                             FrameNoiseSeed(seed, i), &detail);
        changed_fraction[i] = detail.changed_fraction;
        std::vector<std::uint8_t> png;
        cv::imencode(".png", image, png);
        WriteBytesAtomically(directory / ImageName(i), png);
        ++done;
        progressed.notify_one();
      }
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex);
      if (!error) error = std::current_exception();
      failed = true;
      progressed.notify_one();
    }
  };
  const int threads = options.threads > 0
                          ? options.threads
                          : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  std::vector<std::jthread> pool;  // joined on the way out should starting one fail
  for (int i = 0; i < threads; ++i) pool.emplace_back(work);
  std::size_t reported = 0;
  while (true) {
    {
      std::unique_lock<std::mutex> lock(mutex);
      progressed.wait_for(lock, std::chrono::milliseconds(100));
    }
    const std::size_t now = done.load();
    if (now != reported && options.on_progress) options.on_progress(now, planned.size());
    reported = now;
    if (now == planned.size() || failed) break;
  }
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);

  Dataset d;
  d.root = directory;
  SimulationSummary summary;
  for (std::size_t i = 0; i < planned.size(); ++i) {
    DatasetFrame f;
    f.timestamp_s = planned[i].timestamp_s;
    f.image = ImageName(i);
    f.traversal = planned[i].traversal;
    f.changed_fraction = changed_fraction[i];
    f.changed = changed_fraction[i] >= scenario.changed_pixel_fraction;
    d.meta.frame_changed.push_back(f.changed);
    summary.changed_frames += f.changed ? 1 : 0;
    d.frames.push_back(std::move(f));
  }
  const double last = d.frames.empty() ? 0.0 : d.frames.back().timestamp_s;
  for (const auto& o : run.odometry) {
    d.odometry.push_back(o);
    if (o.timestamp_s >= last) break;  // the odometry covers the frames, no more
  }
  std::vector<double> times;  // ground truth at every odometry tick and frame
  for (const auto& o : d.odometry) times.push_back(o.timestamp_s);
  for (const auto& f : d.frames) times.push_back(f.timestamp_s);
  d.ground_truth = TruthAt(run, std::move(times));
  DatasetMeta& m = d.meta;
  m.scenario = scenario.name;
  m.seed = seed;
  m.synthetic_images = true;
  m.synthetic_odometry = true;
  m.note = "simulated by catgraph simulate from scenario '" + scenario.name + "'" +
           (scenario.description.empty() ? "" : ": " + scenario.description);
  const CameraOptions& c = scenario.camera;
  m.camera = {"cylindrical", c.width_px, c.height_px, c.hfov_deg, c.vfov_deg, c.height_m, c.frame_rate_hz};
  m.odometry_rate_hz = scenario.odometry.rate_hz;
  m.changed_regions = scenario.changed_regions;
  m.walls = world.WallSegments();
  for (const Furniture& f : scenario.furniture) {
    m.furniture.push_back({f.name, f.footprint.ToPolygon(), f.height_m, f.traversals});
  }
  WriteDatasetTables(d);

  summary.frames = planned.size();
  for (const auto& t : scenario.traversals) {
    summary.frames_per_traversal.push_back(static_cast<std::size_t>(std::count_if(
        planned.begin(), planned.end(), [&](const PlannedFrame& f) { return f.traversal == t.id; })));
  }
  summary.distance_m = run.distance_m;
  summary.duration_s = last;
  return summary;
}

}  // namespace catgraph
