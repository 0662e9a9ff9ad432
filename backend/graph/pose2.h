// Pose2: a rigid transform in the plane, SE(2), stored as (x, y, theta).
//
// Convention (the same as g2o's SE2 and the CAT-Graph spec, Eq 10): a pose
// T_a_b maps coordinates in frame b to frame a, and composition chains frames,
// T_a_c = T_a_b * T_b_c. A relative measurement u_ab = T_a^-1 * T_b is
// expressed in the frame of the earlier pose. theta is kept wrapped to
// (-pi, pi].
//
// Value type; thread-compatible.
#ifndef CATGRAPH_BACKEND_GRAPH_POSE2_H_
#define CATGRAPH_BACKEND_GRAPH_POSE2_H_

#include <cmath>

#include <Eigen/Core>

#include "backend/graph/angle.h"

namespace catgraph {

class Pose2 {
 public:
  static constexpr int kTangentDim = 3;  // (x, y, theta)
  using Vector = Eigen::Matrix<double, kTangentDim, 1>;

  Pose2() = default;
  Pose2(double x, double y, double theta_rad)
      : x_(x), y_(y), theta_(WrapAngle(theta_rad)) {}
  static Pose2 Identity() { return {}; }

  double x() const { return x_; }
  double y() const { return y_; }
  double theta() const { return theta_; }
  Eigen::Vector2d translation() const { return {x_, y_}; }
  Eigen::Matrix2d rotation() const {
    const double c = std::cos(theta_), s = std::sin(theta_);
    return (Eigen::Matrix2d() << c, -s, s, c).finished();
  }
  Vector ToVector() const { return {x_, y_, theta_}; }

  // T_a_c = T_a_b * T_b_c (the spec's x ⊕ u).
  Pose2 operator*(const Pose2& b) const {
    const double c = std::cos(theta_), s = std::sin(theta_);
    return {x_ + c * b.x_ - s * b.y_, y_ + s * b.x_ + c * b.y_, theta_ + b.theta_};
  }
  Pose2 Inverse() const {
    const double c = std::cos(theta_), s = std::sin(theta_);
    return {-c * x_ - s * y_, s * x_ - c * y_, -theta_};
  }
  // this^-1 * other: `other` expressed in the frame of `this`.
  Pose2 Between(const Pose2& other) const { return Inverse() * other; }
  // Maps a point from this pose's frame to the parent frame.
  Eigen::Vector2d Transform(const Eigen::Vector2d& p) const {
    return rotation() * p + translation();
  }

 private:
  double x_ = 0.0;
  double y_ = 0.0;
  double theta_ = 0.0;
};

// The translation of Interpolate below, alone: no heading to wrap, for the
// particle filters' hot path.
inline Eigen::Vector2d InterpolateTranslation(const Pose2& a, const Pose2& b, double t) {
  return a.translation() + t * (b.translation() - a.translation());
}

// Decoupled interpolation: translation linearly, heading along the shorter
// arc. t = 0 gives a, t = 1 gives b (up to angle wrapping). This is the
// interpolation CAT-Graph uses along an edge (spec §2.2); t outside [0, 1]
// extrapolates.
inline Pose2 Interpolate(const Pose2& a, const Pose2& b, double t) {
  const Eigen::Vector2d p = InterpolateTranslation(a, b, t);
  return {p.x(), p.y(), a.theta() + t * WrapAngle(b.theta() - a.theta())};
}

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_GRAPH_POSE2_H_
