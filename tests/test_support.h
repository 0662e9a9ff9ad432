// Helpers shared by the tests: seeded random poses and data locations.
#ifndef CATGRAPH_TESTS_TEST_SUPPORT_H_
#define CATGRAPH_TESTS_TEST_SUPPORT_H_

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <numbers>
#include <random>
#include <set>
#include <string>

#include "backend/graph/pose2.h"
#include "backend/graph/pose3.h"
#include "backend/pose_graph_optimizer.h"

namespace catgraph::testing {

// Random draws per property checked on random poses.
inline constexpr int kTrials = 1000;

inline Pose2 RandomPose2(std::mt19937_64& rng, double extent_m = 10.0) {
  std::uniform_real_distribution<double> t(-extent_m, extent_m);
  std::uniform_real_distribution<double> a(-std::numbers::pi, std::numbers::pi);
  return {t(rng), t(rng), a(rng)};
}

inline Pose3 RandomPose3(std::mt19937_64& rng, double extent_m = 10.0) {
  std::uniform_real_distribution<double> t(-extent_m, extent_m);
  std::normal_distribution<double> n(0.0, 1.0);
  // A normalised 4D Gaussian is uniform on the rotation group.
  const Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  return {Eigen::Vector3d(t(rng), t(rng), t(rng)), q};
}

inline bool ApproxEqual(const Pose2& a, const Pose2& b, double tol = 1e-9) {
  return std::abs(a.x() - b.x()) <= tol && std::abs(a.y() - b.y()) <= tol &&
         std::abs(WrapAngle(a.theta() - b.theta())) <= tol;
}

inline bool ApproxEqual(const Pose3& a, const Pose3& b, double tol = 1e-9) {
  return (a.translation() - b.translation()).norm() <= tol &&
         RotationAngle(a.rotation().conjugate() * b.rotation()) <= tol;
}

// How an optimisation decided on the injected false closures and on the
// true ones (every other loop closure).
struct InjectedDecisions {
  std::size_t false_accepted = 0;
  std::size_t true_rejected = 0;
  std::size_t true_closures = 0;
};

inline InjectedDecisions CountInjected(const PoseGraphOptimization& result,
                                       const std::set<ClosureId>& injected) {
  InjectedDecisions counts;
  for (const ClosureDecision& d : result.closures) {
    if (injected.contains(d.id)) {
      counts.false_accepted += d.accepted;
    } else {
      counts.true_rejected += !d.accepted;
      ++counts.true_closures;
    }
  }
  return counts;
}

inline std::filesystem::path Fixture(const std::string& name) {
  return std::filesystem::path(CATGRAPH_TEST_FIXTURES) / name;
}

// A fresh, empty directory for one test case: unique per process, so
// parallel ctest runs do not share files.
inline std::filesystem::path TempDir(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("catgraph_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// The whole content of a file ("" if it cannot be read).
inline std::string ReadText(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// The shared pose-graph folder, or an empty path when it is absent.
inline std::filesystem::path SharedPoseGraphs() {
  const std::filesystem::path path = std::filesystem::path(CATGRAPH_SHARED_DATASETS) / "pose-graphs";
  return std::filesystem::is_directory(path) ? path : std::filesystem::path();
}

}  // namespace catgraph::testing

// Declares `root`, the shared pose-graph folder, or ends the test case with
// a warning when ../shared is absent (Catch2 2 has no SKIP).
#define CATGRAPH_SHARED_POSE_GRAPHS_OR_SKIP(root)                                       \
  const std::filesystem::path root = ::catgraph::testing::SharedPoseGraphs();          \
  if (root.empty()) {                                                                   \
    WARN("skipped: shared pose graphs not found at " CATGRAPH_SHARED_DATASETS           \
         "/pose-graphs (set -DCATGRAPH_SHARED_DATASETS=...)");                          \
    return;                                                                             \
  }

#endif  // CATGRAPH_TESTS_TEST_SUPPORT_H_
