#include <numbers>
#include <random>

#include "tests/catch.h"

#include "backend/graph/pose3.h"
#include "tests/test_support.h"

namespace catgraph {
namespace {

using testing::ApproxEqual;
using testing::RandomPose3;
using testing::kTrials;

TEST_CASE("Pose3 composed with its inverse is the identity", "[graph][pose3]") {
  std::mt19937_64 rng(11);
  for (int i = 0; i < kTrials; ++i) {
    const Pose3 p = RandomPose3(rng);
    REQUIRE(ApproxEqual(p * p.Inverse(), Pose3::Identity()));
    REQUIRE(ApproxEqual(p.Inverse() * p, Pose3::Identity()));
    REQUIRE(std::abs(p.rotation().norm() - 1.0) < 1e-12);
  }
}

TEST_CASE("Pose3 composition is associative and Between undoes it", "[graph][pose3]") {
  std::mt19937_64 rng(12);
  for (int i = 0; i < kTrials; ++i) {
    const Pose3 a = RandomPose3(rng), b = RandomPose3(rng), c = RandomPose3(rng);
    REQUIRE(ApproxEqual((a * b) * c, a * (b * c)));
    REQUIRE(ApproxEqual(a * a.Between(b), b));
    REQUIRE(ApproxEqual(a.Between(b), b.Between(a).Inverse()));
    const Eigen::Vector3d p(1.0, -2.0, 0.5);
    REQUIRE((a.Transform(b.Transform(p)) - (a * b).Transform(p)).norm() < 1e-9);
  }
}

TEST_CASE("Pose3 agrees with Pose2 for planar motion", "[graph][pose3]") {
  std::mt19937_64 rng(13);
  for (int i = 0; i < kTrials; ++i) {
    const Pose2 a2 = testing::RandomPose2(rng), b2 = testing::RandomPose2(rng);
    auto lift = [](const Pose2& p) {
      return Pose3(Eigen::Vector3d(p.x(), p.y(), 0.0),
                   Eigen::Quaterniond(Eigen::AngleAxisd(p.theta(), Eigen::Vector3d::UnitZ())));
    };
    REQUIRE(ApproxEqual(lift(a2 * b2), lift(a2) * lift(b2)));
    REQUIRE(ApproxEqual(lift(a2.Between(b2)), lift(a2).Between(lift(b2))));
  }
}

TEST_CASE("Pose3 interpolation hits its end points and halves the rotation", "[graph][pose3]") {
  std::mt19937_64 rng(14);
  for (int i = 0; i < kTrials; ++i) {
    const Pose3 a = RandomPose3(rng), b = RandomPose3(rng);
    REQUIRE(ApproxEqual(Interpolate(a, b, 0.0), a));
    REQUIRE(ApproxEqual(Interpolate(a, b, 1.0), b));
    const Pose3 mid = Interpolate(a, b, 0.5);
    const double full = RotationAngle(a.rotation().conjugate() * b.rotation());
    const double half = RotationAngle(a.rotation().conjugate() * mid.rotation());
    REQUIRE(half == Approx(full / 2.0).margin(1e-9));
  }
}

TEST_CASE("Pose3 normalises a non-unit quaternion", "[graph][pose3]") {
  const Pose3 p(Eigen::Vector3d::Zero(), Eigen::Quaterniond(2.0, 0.0, 0.0, 0.0));
  CHECK(p.rotation().w() == Approx(1.0));
  CHECK(RotationAngle(Eigen::Quaterniond(-1.0, 0.0, 0.0, 0.0)) == Approx(0.0).margin(1e-15));
}

}  // namespace
}  // namespace catgraph
