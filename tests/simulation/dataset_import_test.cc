// `catgraph import`'s library: recordings in the folder, KITTI and TUM RGB-D
// layouts written from a known path, imported back and compared with it.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <numbers>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "tests/catch.h"

#include "backend/io/dataset.h"
#include "backend/io/file_error.h"
#include "simulation/dataset_import.h"
#include "tests/test_support.h"

namespace catgraph {
namespace {

// A ground robot's path: forward along an S-bend, a reverse, a sideways
// slide, at 10 Hz; 2D poses relative to the first (at the origin facing +x).
std::vector<TimedPose2> Path(int n) {
  std::vector<TimedPose2> path;
  Pose2 pose;
  for (int k = 0; k < n; ++k) {
    path.push_back({0.1 * k, pose});
    const double turn = 0.05 * std::sin(0.05 * k);
    const Pose2 step = k % 40 == 39 ? Pose2(-0.05, 0.0, 0.0) : k % 50 == 49 ? Pose2(0.0, 0.03, 0.0)
                                                                            : Pose2(0.1, 0.0, turn);
    pose = pose * step;
  }
  return path;
}

// The camera's rotation (optical convention: columns right, down, forward)
// and position for 2D pose `p` in a world whose up is `up`, whose first
// camera looks along `forward0` and stands `height` above the plane.
struct CameraPose {
  Eigen::Matrix3d rotation;
  Eigen::Vector3d translation;
};
CameraPose Camera(const Pose2& p, const Eigen::Vector3d& up, const Eigen::Vector3d& forward0, double height) {
  const Eigen::Vector3d e1 = forward0.normalized(), e2 = up.cross(e1);
  const Eigen::Vector3d forward = std::cos(p.theta()) * e1 + std::sin(p.theta()) * e2;
  const Eigen::Vector3d down = -up;
  CameraPose c;
  c.rotation.col(0) = down.cross(forward);
  c.rotation.col(1) = down;
  c.rotation.col(2) = forward;
  c.translation = p.x() * e1 + p.y() * e2 + height * up + Eigen::Vector3d(3.0, -2.0, 1.0);
  return c;
}

void WriteImage(const std::filesystem::path& path, int k) {
  cv::Mat image(24, 32, CV_8UC1, cv::Scalar(static_cast<double>((k * 37) % 256)));
  REQUIRE(cv::imwrite(path.string(), image));
}

void CheckPath(const std::vector<TimedPose2>& expected, const Dataset& d, double first_time) {
  for (const TimedPose2& e : expected) {
    if (e.timestamp_s < first_time || e.timestamp_s > d.frames.back().timestamp_s) continue;
    const Pose2 got = InterpolatePose(d.ground_truth, e.timestamp_s);
    INFO("t = " << e.timestamp_s);
    // groundtruth.csv holds micrometres and nanoradians.
    CHECK(got.x() == Approx(e.pose.x()).margin(1e-6));
    CHECK(got.y() == Approx(e.pose.y()).margin(1e-6));
    CHECK(std::remainder(got.theta() - e.pose.theta(), 2.0 * std::numbers::pi) == Approx(0.0).margin(1e-8));
  }
}

TEST_CASE("wheel odometry along a path: exact without noise, drifting a little with the simulator's",
          "[simulation][import]") {
  const std::vector<TimedPose2> path = Path(300);
  OdometryOptions exact;
  exact.noise_m_per_sqrt_m = exact.left_scale_error = exact.right_scale_error = exact.track_error = 0.0;
  const std::vector<TimedPose2> odometry = WheelOdometryAlong(path, 0.33, exact, 1);
  REQUIRE(odometry.size() == path.size());
  for (std::size_t k = 0; k < path.size(); ++k) {
    INFO("pose " << k);
    CHECK(odometry[k].timestamp_s == path[k].timestamp_s);
    CHECK((odometry[k].pose.translation() - path[k].pose.translation()).norm() < 1e-9);
    CHECK(std::remainder(odometry[k].pose.theta() - path[k].pose.theta(), 2.0 * std::numbers::pi) ==
          Approx(0.0).margin(1e-9));
  }
  const std::vector<TimedPose2> noisy = WheelOdometryAlong(path, 0.33, OdometryOptions{}, 7);
  const std::vector<TimedPose2> again = WheelOdometryAlong(path, 0.33, OdometryOptions{}, 7);
  const std::vector<TimedPose2> other = WheelOdometryAlong(path, 0.33, OdometryOptions{}, 8);
  CHECK(noisy.back().pose.ToVector() == again.back().pose.ToVector());
  CHECK(noisy.back().pose.ToVector() != other.back().pose.ToVector());
  double length = 0.0;
  for (std::size_t k = 1; k < path.size(); ++k) {
    length += (path[k].pose.translation() - path[k - 1].pose.translation()).norm();
  }
  const double drift = (noisy.back().pose.translation() - path.back().pose.translation()).norm();
  CHECK(drift > 0.0);
  CHECK(drift < 0.05 * length);  // the simulator's model: a few per cent of the distance
}

TEST_CASE("the KITTI layout imports with its poses on the ground plane and odometry made from them",
          "[simulation][import]") {
  const auto root = testing::TempDir("import_kitti");
  const std::vector<TimedPose2> path = Path(120);
  std::filesystem::create_directories(root / "seq" / "image_0");
  std::ofstream times(root / "seq" / "times.txt"), poses(root / "poses.txt");
  times << std::setprecision(17);
  poses << std::setprecision(17);
  // KITTI's world is the first camera's frame: y down.
  for (std::size_t k = 0; k < path.size(); ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "%06zu.png", k);
    WriteImage(root / "seq" / "image_0" / name, static_cast<int>(k));
    times << path[k].timestamp_s << "\n";
    const CameraPose c = Camera(path[k].pose, Eigen::Vector3d(0.0, -1.0, 0.0), Eigen::Vector3d(0.0, 0.0, 1.0), 1.65);
    for (int r = 0; r < 3; ++r) {
      poses << c.rotation(r, 0) << ' ' << c.rotation(r, 1) << ' ' << c.rotation(r, 2) << ' ' << c.translation(r)
            << (r < 2 ? ' ' : '\n');
    }
  }
  times.close();
  poses.close();
  ImportOptions options;
  options.poses = root / "poses.txt";
  const ImportSummary s = ImportDataset(ImportLayout::kKitti, root / "seq", root / "out", options);
  CHECK(s.frames == 120);
  CHECK(s.left_out == 0);
  CHECK(s.traversals == 1);
  CHECK(s.synthetic_odometry);
  const Dataset d = ReadDataset(root / "out");
  REQUIRE(d.frames.size() == 120);
  CHECK(d.meta.synthetic_odometry);
  CHECK_FALSE(d.meta.synthetic_ground_truth);
  CHECK(d.meta.camera.width_px == 32);
  CHECK(d.meta.camera.frame_rate_hz == Approx(10.0));
  CHECK_THAT(d.meta.note, Catch::Contains("wheel-odometry model"));
  CheckPath(path, d, 0.0);
  CHECK(std::filesystem::exists(root / "out" / "images" / "000119.png"));

  // A line of 11 numbers: the file and the line named.
  {
    std::ofstream bad(root / "bad.txt");
    bad << "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1\n";
  }
  options.poses = root / "bad.txt";
  CHECK_THROWS_WITH(ImportDataset(ImportLayout::kKitti, root / "seq", root / "out2", options),
                    Catch::Contains("bad.txt:2") && Catch::Contains("expected 12 numbers"));
  std::filesystem::remove_all(root);
}

TEST_CASE("the TUM RGB-D layout imports: mocap poses onto the floor, frames before them left out",
          "[simulation][import]") {
  const auto root = testing::TempDir("import_tum");
  const std::vector<TimedPose2> path = Path(200);
  std::filesystem::create_directories(root / "rgb");
  std::ofstream list(root / "rgb.txt"), truth(root / "groundtruth.txt");
  list << std::setprecision(17) << "# color images\n# timestamp filename\n";
  truth << std::setprecision(17) << "# ground truth trajectory\n# timestamp tx ty tz qx qy qz qw\n";
  // A mocap world with z up, the first camera looking along (1, 1, 0).
  const double t0 = 1305031102.0;
  for (std::size_t k = 0; k < path.size(); ++k) {
    const CameraPose c = Camera(path[k].pose, Eigen::Vector3d::UnitZ(), Eigen::Vector3d(1.0, 1.0, 0.0), 0.6);
    const Eigen::Quaterniond q(c.rotation);
    truth << t0 + path[k].timestamp_s << ' ' << c.translation.x() << ' ' << c.translation.y() << ' '
          << c.translation.z() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z() << ' ' << q.w() << "\n";
  }
  // Images at 30 Hz between the poses, some before the mocap starts.
  int images = 0;
  for (double t = -0.5; t < path.back().timestamp_s; t = -0.5 + (++images) / 30.0) {
    const std::string name = "rgb/" + std::to_string(images) + ".png";
    WriteImage(root / name, images);
    list << t0 + t << ' ' << name << "\n";
  }
  list.close();
  truth.close();
  const ImportSummary s = ImportDataset(ImportLayout::kTum, root, root / "out", {});
  CHECK(s.left_out == 15);
  CHECK(s.frames == static_cast<std::size_t>(images) - 15);
  const Dataset d = ReadDataset(root / "out");
  CHECK(d.frames.size() == s.frames);
  CHECK(d.meta.synthetic_odometry);
  CHECK_THAT(d.meta.note, Catch::Contains("15 frames outside"));
  // The ground plane's frame puts the first pose (not the first frame) at the origin.
  std::vector<TimedPose2> shifted = path;
  for (auto& p : shifted) p.timestamp_s += t0;
  CheckPath(shifted, d, d.frames.front().timestamp_s);
  std::filesystem::remove_all(root);
}

TEST_CASE("an image folder imports with its odometry and poses; a gap starts a traversal",
          "[simulation][import]") {
  const auto root = testing::TempDir("import_folder");
  const std::vector<TimedPose2> path = Path(100);
  std::filesystem::create_directories(root / "images");
  std::ofstream odometry(root / "odometry.csv"), poses(root / "poses.csv");
  odometry << std::setprecision(17) << "timestamp,x,y,theta\n";
  poses << std::setprecision(17) << "timestamp,x,y,theta\n";
  // Frames every 0.2 s inside the poses' time range, named by Unix time in
  // nanoseconds; a 20 s pause halfway.
  std::vector<TimedPose2> timed = path;
  for (std::size_t k = 0; k < timed.size(); ++k) timed[k].timestamp_s += 1.7e9 + (k >= 50 ? 20.0 : 0.0);
  for (std::size_t k = 0; k < timed.size(); ++k) {
    const Pose2& p = timed[k].pose;
    odometry << timed[k].timestamp_s << ',' << p.x() + 0.01 << ',' << p.y() << ',' << p.theta() << "\n";
    poses << timed[k].timestamp_s << ',' << p.x() << ',' << p.y() << ',' << p.theta() << "\n";
    if (k % 2 == 0 && k > 0 && k + 2 < timed.size()) {
      WriteImage(root / "images" / (std::to_string(static_cast<long long>(std::llround(timed[k].timestamp_s * 1e9))) + ".jpg"),
                 static_cast<int>(k));
    }
  }
  odometry.close();
  poses.close();
  ImportOptions options;
  options.odometry = root / "odometry.csv";
  options.poses = root / "poses.csv";
  const ImportSummary s = ImportDataset(ImportLayout::kFolder, root / "images", root / "out", options);
  CHECK(s.traversals == 2);
  CHECK_FALSE(s.synthetic_odometry);
  const Dataset d = ReadDataset(root / "out");
  CHECK_FALSE(d.meta.synthetic_odometry);
  CHECK(d.Traversals() == std::vector<int>{1, 2});
  CHECK(d.frames.size() == 48);
  CHECK(InterpolatePose(d.odometry, d.frames[3].timestamp_s).x() ==
        Approx(InterpolatePose(d.ground_truth, d.frames[3].timestamp_s).x() + 0.01).margin(1e-6));
  CheckPath(timed, d, d.frames.front().timestamp_s);

  // Without odometry or poses: said so.
  CHECK_THROWS_WITH(ImportDataset(ImportLayout::kFolder, root / "images", root / "out2", {}),
                    Catch::Contains("needs an odometry CSV, a pose CSV or both"));
  // A pose CSV with another header: the file and the line.
  {
    std::ofstream bad(root / "bad.csv");
    bad << "# recorded on the lab robot\ntime,x,y,yaw\n0,0,0,0\n";
  }
  options.poses = root / "bad.csv";
  CHECK_THROWS_WITH(ImportDataset(ImportLayout::kFolder, root / "images", root / "out3", options),
                    Catch::Contains("bad.csv:2") && Catch::Contains("timestamp,x,y,theta"));
  std::filesystem::remove_all(root);
}

}  // namespace
}  // namespace catgraph
