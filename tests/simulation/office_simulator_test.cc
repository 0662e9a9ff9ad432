// The office simulator: determinism, image content, change labels, odometry
// quality, and the renderer's geometry against values computed by hand.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <vector>

#include "tests/catch.h"
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "backend/io/dataset.h"
#include "simulation/office_simulator.h"
#include "simulation/scenario.h"
#include "tests/test_support.h"

namespace catgraph {
namespace {

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

std::vector<std::filesystem::path> FilesUnder(const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir)) {
    if (e.is_regular_file()) files.push_back(std::filesystem::relative(e.path(), dir));
  }
  std::sort(files.begin(), files.end());
  return files;
}

// A grey, blurred, 64 × 24 thumbnail: the "simple image distance" compares
// these by mean absolute difference.
cv::Mat1f Thumbnail(const cv::Mat3b& image) {
  cv::Mat grey, small;
  cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  cv::resize(grey, small, cv::Size(64, 24), 0, 0, cv::INTER_AREA);
  cv::Mat1f f;
  small.convertTo(f, CV_32F);
  return f;
}

TEST_CASE("the same seed gives a byte-identical dataset, another seed other noise",
          "[simulation][office]") {
  const Scenario scenario = LoadScenario("office-static");
  const auto dir = testing::TempDir("sim_determinism");
  SimulationOptions options;
  options.max_frames = 30;
  options.seed = 11;
  SimulateDataset(scenario, dir / "a", options);
  options.threads = 1;  // the thread count must not matter
  SimulateDataset(scenario, dir / "b", options);
  options.seed = 12;
  SimulateDataset(scenario, dir / "c", options);

  const auto files = FilesUnder(dir / "a");
  REQUIRE(files.size() == 30 + 4);
  REQUIRE(FilesUnder(dir / "b") == files);
  for (const auto& f : files) {
    INFO(f.string());
    CHECK(testing::ReadText(dir / "a" / f) == testing::ReadText(dir / "b" / f));
  }
  // Another seed: the same path and world, other odometry and image noise.
  CHECK(testing::ReadText(dir / "a" / "groundtruth.csv") == testing::ReadText(dir / "c" / "groundtruth.csv"));
  CHECK(testing::ReadText(dir / "a" / "odometry.csv") != testing::ReadText(dir / "c" / "odometry.csv"));
  CHECK(testing::ReadText(dir / "a" / "images/000010.png") !=
        testing::ReadText(dir / "c" / "images/000010.png"));
  std::filesystem::remove_all(dir);
}

TEST_CASE("a simulated dataset reads back with every frame inside its odometry",
          "[simulation][office][dataset]") {
  const auto dir = testing::TempDir("sim_readback");
  SimulationOptions options;
  options.max_frames = 50;
  const auto summary = SimulateDataset(LoadScenario("office-change"), dir, options);
  const Dataset d = ReadDataset(dir);
  CHECK(d.frames.size() == 50);
  CHECK(summary.frames == 50);
  CHECK(d.meta.scenario == "office-change");
  CHECK(d.meta.synthetic_images);
  CHECK(d.meta.camera.width_px == 261);
  CHECK(d.meta.camera.height_px == 101);
  CHECK(d.meta.changed_regions.size() == 1);
  CHECK(d.meta.walls.size() == 4 * (1 + 7 + 13));  // building, offices, pillars
  REQUIRE(d.HasGroundTruth());
  // Frames at 7.5 Hz, odometry at 10 Hz, ground truth at both.
  CHECK(d.frames[1].timestamp_s - d.frames[0].timestamp_s == Approx(1.0 / 7.5));
  CHECK(d.odometry[1].timestamp_s - d.odometry[0].timestamp_s == Approx(0.1));
  CHECK(d.frames.back().timestamp_s <= d.odometry.back().timestamp_s);
  // The first frame is at the route's start (1.2, 12), facing along it (south).
  const Pose2 start = InterpolatePose(d.ground_truth, d.frames[0].timestamp_s);
  CHECK(start.x() == Approx(1.2));
  CHECK(start.y() == Approx(12.0));
  CHECK(start.theta() == Approx(-std::numbers::pi / 2));
  const cv::Mat image = cv::imread(d.ImagePath(0).string());
  CHECK(image.cols == 261);
  CHECK(image.rows == 101);
  std::filesystem::remove_all(dir);
}

TEST_CASE("rendered frames have enough SIFT keypoints for a vocabulary", "[simulation][office][slow]") {
  const Scenario scenario = LoadScenario("office-static");
  const RobotRun run = DriveScenario(scenario, 1);
  const auto frames = PlanFrames(run, scenario.camera.frame_rate_hz, 0);
  const OfficeWorld world = MakeWorld(scenario);
  auto sift = cv::SIFT::create();
  std::vector<double> counts;
  for (std::size_t i = 0; i < frames.size(); i += frames.size() / 80) {
    cv::Mat grey;
    cv::cvtColor(world.Render(frames[i].T_world_camera, frames[i].traversal, i), grey, cv::COLOR_BGR2GRAY);
    std::vector<cv::KeyPoint> keypoints;
    sift->detect(grey, keypoints);
    counts.push_back(static_cast<double>(keypoints.size()));
  }
  INFO("median SIFT keypoints " << Median(counts) << " over " << counts.size() << " frames");
  CHECK(Median(counts) >= 50.0);
  CHECK(*std::min_element(counts.begin(), counts.end()) >= 10.0);
}

TEST_CASE("office-change: views in the refurnished corridor differ far more than elsewhere",
          "[simulation][office][slow]") {
  const Scenario scenario = LoadScenario("office-change");
  const RobotRun run = DriveScenario(scenario, 1);
  const auto frames = PlanFrames(run, scenario.camera.frame_rate_hz, 0);
  const OfficeWorld world = MakeWorld(scenario);
  std::vector<std::size_t> first;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    if (frames[i].traversal == 1) first.push_back(i);
  }
  std::vector<double> inside, outside;
  for (std::size_t i = 0; i < frames.size(); i += 3) {
    if (frames[i].traversal != 2) continue;
    const Pose2& p = frames[i].T_world_camera;
    // The traversal-1 frame nearest in space with a similar heading.
    std::size_t best = first.front();
    double best_d = 1e9;
    for (const std::size_t j : first) {
      const Pose2& q = frames[j].T_world_camera;
      if (std::abs(WrapAngle(p.theta() - q.theta())) > 0.5) continue;
      const double d = (p.translation() - q.translation()).norm();
      if (d < best_d) best_d = d, best = j;
    }
    if (best_d > 0.3) continue;  // turning or nothing comparable
    RenderDetail detail;
    const cv::Mat1f now = Thumbnail(world.Render(p, 2, FrameNoiseSeed(1, i), &detail));
    const cv::Mat1f then = Thumbnail(world.Render(frames[best].T_world_camera, 1, FrameNoiseSeed(1, best)));
    const double distance = cv::mean(cv::abs(now - then))[0];
    (detail.changed_fraction >= scenario.changed_pixel_fraction ? inside : outside).push_back(distance);
  }
  INFO("inside: " << inside.size() << " frames, median distance " << Median(inside)
                  << "; outside: " << outside.size() << " frames, median " << Median(outside));
  REQUIRE(inside.size() >= 50);
  REQUIRE(outside.size() >= 200);
  CHECK(Median(inside) > 2.0 * Median(outside));
}

TEST_CASE("default odometry drifts 1-5% of the distance over one traversal", "[simulation][office]") {
  const Scenario scenario = LoadScenario("office-static");
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const RobotRun run = DriveScenario(scenario, seed);
    const double end_s = run.traversal_end_s.front();
    // The odometry frame placed on the true start pose.
    const Pose2 T_world_odom = run.truth.front().pose * run.odometry.front().pose.Inverse();
    const Pose2 estimate = T_world_odom * InterpolatePose(run.odometry, end_s);
    const Pose2 truth = InterpolatePose(run.truth, end_s);
    const double error_fraction = (estimate.translation() - truth.translation()).norm() / run.distance_m.front();
    INFO("seed " << seed << ": end-point error " << 100.0 * error_fraction << "% of "
                 << run.distance_m.front() << " m");
    CHECK(run.distance_m.front() == Approx(84.5).margin(1.0));
    CHECK(error_fraction >= 0.01);
    CHECK(error_fraction <= 0.05);
  }
}

TEST_CASE("the split traversal drives the parallel corridor, the first does not", "[simulation][office]") {
  const RobotRun run = DriveScenario(LoadScenario("office-split"), 1);
  double max_y_first = 0.0, max_y_second_south_half = 0.0;
  for (std::size_t i = 0; i < run.truth.size(); ++i) {
    const Pose2& p = run.truth[i].pose;
    if (p.x() < 8.0 || p.x() > 24.0) continue;
    if (p.y() > 12.0) continue;  // the cross corridor
    (run.traversal[i] == 1 ? max_y_first : max_y_second_south_half) =
        std::max(run.traversal[i] == 1 ? max_y_first : max_y_second_south_half, p.y());
  }
  CHECK(max_y_first == Approx(1.2).margin(0.05));
  CHECK(max_y_second_south_half == Approx(7.35).margin(0.1));
}

TEST_CASE("office-lighting darkens the dim region on the second traversal only", "[simulation][office]") {
  const Scenario scenario = LoadScenario("office-lighting");
  const OfficeWorld world = MakeWorld(scenario);
  const Pose2 in_region(1.2, 10.0, -std::numbers::pi / 2.0);  // facing south along x = 1.2
  const Pose2 elsewhere(15.0, 15.0, std::numbers::pi);
  const double ratio_in = cv::mean(world.Render(in_region, 2, 0))[1] / cv::mean(world.Render(in_region, 1, 0))[1];
  const double ratio_out = cv::mean(world.Render(elsewhere, 2, 0))[1] / cv::mean(world.Render(elsewhere, 1, 0))[1];
  CHECK(ratio_in < 0.6);
  CHECK(ratio_out == Approx(1.0).margin(0.01));
  RenderDetail detail;
  world.Render(in_region, 1, 0, &detail);
  CHECK(detail.changed_fraction > 0.5);  // both traversals' views differ there
}

// The pinhole-in-elevation numbers the renderer uses (office_world.h).
struct RowGeometry {
  explicit RowGeometry(const CameraOptions& c)
      : fv(0.5 * c.height_px / std::tan(0.5 * c.vfov_deg * std::numbers::pi / 180.0)),
        cy(0.5 * (c.height_px - 1)),
        centre((c.width_px - 1) / 2) {}
  double TanElevation(int row) const { return (cy - row) / fv; }
  double fv, cy;
  int centre;
};

// A 10 m × 10 m room without furniture except a 0.5 m box 2 m ahead.
OfficeWorld Room(bool with_box) {
  FloorPlan plan;
  plan.building = {0, 0, 10, 10};
  plan.ceiling_height_m = 3.0;
  std::vector<Furniture> furniture;
  if (with_box) furniture.push_back({"box", FurnitureStyle::kBoxes, {7.0, 4.5, 8.0, 5.5}, 0.5, {1}});
  CameraOptions camera;
  camera.noise_sigma = 0.0;
  return OfficeWorld(plan, furniture, {}, camera, {1});
}

TEST_CASE("the renderer projects walls, floor and ceiling where the camera model puts them",
          "[simulation][render]") {
  const OfficeWorld world = Room(false);
  const CameraOptions& c = world.camera();
  RenderDetail detail;
  world.Render(Pose2(5.0, 5.0, 0.0), 1, 0, &detail);
  const RowGeometry g(c);
  const double fv = g.fv, cy = g.cy;
  const int centre = g.centre;
  // The wall 5 m ahead spans tan(el) from -1/5 (floor) to 2/5 (ceiling).
  const int floor_row = static_cast<int>(std::ceil(cy + fv * 1.0 / 5.0));
  const int ceiling_row = static_cast<int>(std::floor(cy - fv * 2.0 / 5.0));
  for (int r = 0; r < c.height_px; ++r) {
    INFO("row " << r);
    const auto kind = static_cast<SurfaceKind>(detail.surface(r, centre));
    if (r > floor_row) CHECK(kind == SurfaceKind::kFloor);
    if (r < ceiling_row) CHECK(kind == SurfaceKind::kCeiling);
    if (r < floor_row - 1 && r > ceiling_row + 1) {
      CHECK(kind == SurfaceKind::kWall);
      CHECK(detail.depth_m(r, centre) == Approx(5.0).epsilon(1e-6));
    }
  }
  // A column 30 degrees to the left sees the wall at 5 / cos 30.
  const double pixel_deg = c.hfov_deg / c.width_px;
  const int left = static_cast<int>(std::lround((c.width_px - 1) / 2.0 - 30.0 / pixel_deg));
  const double bearing = ((c.width_px - 1) / 2.0 - left) * pixel_deg * std::numbers::pi / 180.0;
  CHECK(detail.depth_m(static_cast<int>(cy), left) == Approx(5.0 / std::cos(bearing)).epsilon(1e-6));
}

TEST_CASE("furniture occludes the wall below its height and shows its top from above",
          "[simulation][render]") {
  const OfficeWorld world = Room(true);
  const CameraOptions& c = world.camera();
  RenderDetail detail;
  world.Render(Pose2(5.0, 5.0, 0.0), 1, 0, &detail);
  const RowGeometry g(c);
  const int centre = g.centre;
  for (int r = 0; r < c.height_px; ++r) {
    const double tan_el = g.TanElevation(r);
    INFO("row " << r << ", tan(elevation) " << tan_el);
    const auto kind = static_cast<SurfaceKind>(detail.surface(r, centre));
    const double depth = detail.depth_m(r, centre);
    if (tan_el < -0.51 && tan_el > -0.2 * 5) {
      CHECK(kind == SurfaceKind::kFloor);  // the floor before the box
    } else if (tan_el > -0.49 && tan_el < -0.26) {
      CHECK(kind == SurfaceKind::kFurniture);  // its front face at 2 m
      CHECK(depth == Approx(2.0).epsilon(1e-6));
    } else if (tan_el > -0.24 && tan_el < -0.17) {
      CHECK(kind == SurfaceKind::kFurniture);  // its top, 0.5 m below the camera
      CHECK(depth == Approx(-0.5 / tan_el).epsilon(1e-6));
    } else if (tan_el > -0.16 && tan_el < 0.39) {
      CHECK(kind == SurfaceKind::kWall);  // over the box to the wall
      CHECK(depth == Approx(5.0).epsilon(1e-6));
    }
  }
}

TEST_CASE("furniture missing in a traversal marks the pixels it would cover as changed",
          "[simulation][render]") {
  FloorPlan plan;
  plan.building = {0, 0, 10, 10};
  CameraOptions camera;
  const OfficeWorld world(plan, {{"box", FurnitureStyle::kBoxes, {7.0, 4.0, 8.0, 6.0}, 2.0, {2}}}, {},
                          camera, {1, 2});
  RenderDetail with, without;
  world.Render(Pose2(5.0, 5.0, 0.0), 2, 0, &with);
  world.Render(Pose2(5.0, 5.0, 0.0), 1, 0, &without);
  CHECK(with.changed_fraction > 0.1);
  CHECK(without.changed_fraction == Approx(with.changed_fraction));
  RenderDetail away;
  world.Render(Pose2(5.0, 5.0, std::numbers::pi), 1, 0, &away);
  CHECK(away.changed_fraction == 0.0);
}

}  // namespace
}  // namespace catgraph
