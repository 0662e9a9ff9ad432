#include <cmath>
#include <numbers>
#include <random>

#include "tests/catch.h"

#include "backend/graph/pose2.h"
#include "tests/test_support.h"

namespace catgraph {
namespace {

using testing::ApproxEqual;
using testing::RandomPose2;
using testing::kTrials;
constexpr double kPi = std::numbers::pi;

TEST_CASE("WrapAngle maps every angle into the half-open interval from -pi to pi", "[graph][pose2]") {
  CHECK(WrapAngle(kPi) == Approx(kPi));
  CHECK(WrapAngle(-kPi) == Approx(kPi));
  CHECK(WrapAngle(3.0 * kPi) == Approx(kPi));
  CHECK(WrapAngle(0.5) == Approx(0.5));
  CHECK(WrapAngle(2.0 * kPi + 0.25) == Approx(0.25));
  CHECK(WrapAngle(-2.0 * kPi - 0.25) == Approx(-0.25));
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> angle(-100.0, 100.0);
  for (int i = 0; i < kTrials; ++i) {
    const double a = angle(rng);
    const double w = WrapAngle(a);
    REQUIRE(w > -kPi);
    REQUIRE(w <= kPi);
    // Same rotation: the difference is a whole number of turns.
    const double turns = (a - w) / (2.0 * kPi);
    REQUIRE(turns == Approx(std::round(turns)).margin(1e-9));
  }
}

TEST_CASE("WrapAngle returns an angle already in range unchanged, to the last bit", "[graph][pose2]") {
  // What std::remainder gives for it, so skipping the call changes no result.
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  for (int i = 0; i < kTrials; ++i) {
    const double a = angle(rng);
    REQUIRE(WrapAngle(a) == a);
    REQUIRE(std::remainder(a, 2.0 * kPi) == a);
  }
  const double just_above_minus_pi = std::nextafter(-kPi, 0.0);
  CHECK(WrapAngle(just_above_minus_pi) == just_above_minus_pi);
  CHECK(WrapAngle(kPi) == kPi);
  CHECK(WrapAngle(-kPi) == kPi);
  CHECK(WrapAngle(std::nextafter(kPi, 4.0)) < 0.0);
}

TEST_CASE("Pose2 headings just either side of pi compose across the cut", "[graph][pose2]") {
  const Pose2 a(0.0, 0.0, kPi - 0.1);
  const Pose2 b(0.0, 0.0, 0.2);
  CHECK((a * b).theta() == Approx(-kPi + 0.1));
  CHECK(a.Between(Pose2(0.0, 0.0, -kPi + 0.1)).theta() == Approx(0.2));
}

TEST_CASE("Pose2 composed with its inverse is the identity", "[graph][pose2]") {
  std::mt19937_64 rng(1);
  for (int i = 0; i < kTrials; ++i) {
    const Pose2 p = RandomPose2(rng);
    REQUIRE(ApproxEqual(p * p.Inverse(), Pose2::Identity()));
    REQUIRE(ApproxEqual(p.Inverse() * p, Pose2::Identity()));
    REQUIRE(ApproxEqual(p.Inverse().Inverse(), p));
  }
}

TEST_CASE("Pose2 composition is associative and Between undoes it", "[graph][pose2]") {
  std::mt19937_64 rng(2);
  for (int i = 0; i < kTrials; ++i) {
    const Pose2 a = RandomPose2(rng), b = RandomPose2(rng), c = RandomPose2(rng);
    REQUIRE(ApproxEqual((a * b) * c, a * (b * c)));
    REQUIRE(ApproxEqual(a * a.Between(b), b));
    REQUIRE(ApproxEqual(a.Between(b), b.Between(a).Inverse()));
  }
}

TEST_CASE("Pose2 composition follows the spec's Eq 10", "[graph][pose2]") {
  // x ⊕ u with x = (1, 2, 90°), u = (3, 0, 0): moving forward along +y.
  const Pose2 x(1.0, 2.0, kPi / 2.0);
  const Pose2 y = x * Pose2(3.0, 0.0, 0.0);
  CHECK(y.x() == Approx(1.0).margin(1e-12));
  CHECK(y.y() == Approx(5.0));
  CHECK(y.theta() == Approx(kPi / 2.0));
  const Eigen::Vector2d p = x.Transform(Eigen::Vector2d(1.0, 0.0));
  CHECK(p.x() == Approx(1.0).margin(1e-12));
  CHECK(p.y() == Approx(3.0));
}

TEST_CASE("Pose2 interpolation hits its end points and takes the short way round",
          "[graph][pose2]") {
  std::mt19937_64 rng(3);
  for (int i = 0; i < kTrials; ++i) {
    const Pose2 a = RandomPose2(rng), b = RandomPose2(rng);
    REQUIRE(ApproxEqual(Interpolate(a, b, 0.0), a));
    REQUIRE(ApproxEqual(Interpolate(a, b, 1.0), b));
    const Pose2 mid = Interpolate(a, b, 0.5);
    REQUIRE(std::abs(WrapAngle(mid.theta() - a.theta())) <= kPi / 2.0 + 1e-12);
  }
  const Pose2 m = Interpolate(Pose2(0, 0, kPi - 0.1), Pose2(2, 0, -kPi + 0.1), 0.5);
  CHECK(m.x() == Approx(1.0));
  CHECK(std::abs(m.theta()) == Approx(kPi));
}

}  // namespace
}  // namespace catgraph
