// Pose3: a rigid transform in space, SE(3), stored as a translation and a unit
// quaternion (Eigen's (w, x, y, z) object; files use g2o's qx qy qz qw order).
//
// Same conventions as Pose2: T_a_c = T_a_b * T_b_c, Between(a, b) = a^-1 * b.
// The quaternion is normalised on construction; q and -q are the same
// rotation, and operator== is not provided for that reason: compare with
// ApproxEqual.
//
// Value type; thread-compatible.
#ifndef CATGRAPH_BACKEND_GRAPH_POSE3_H_
#define CATGRAPH_BACKEND_GRAPH_POSE3_H_

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace catgraph {

class Pose3 {
 public:
  static constexpr int kTangentDim = 6;  // (translation, rotation)
  using Vector = Eigen::Matrix<double, kTangentDim, 1>;

  Pose3() = default;
  // `rotation` need not be unit length but must be non-zero; it is normalised.
  Pose3(const Eigen::Vector3d& translation, const Eigen::Quaterniond& rotation)
      : translation_(translation), rotation_(rotation.normalized()) {}
  static Pose3 Identity() { return {}; }

  const Eigen::Vector3d& translation() const { return translation_; }
  const Eigen::Quaterniond& rotation() const { return rotation_; }

  Pose3 operator*(const Pose3& b) const {
    return {translation_ + rotation_ * b.translation_, rotation_ * b.rotation_};
  }
  Pose3 Inverse() const {
    const Eigen::Quaterniond r_inv = rotation_.conjugate();
    return {-(r_inv * translation_), r_inv};
  }
  Pose3 Between(const Pose3& other) const { return Inverse() * other; }
  Eigen::Vector3d Transform(const Eigen::Vector3d& p) const {
    return rotation_ * p + translation_;
  }

 private:
  Eigen::Vector3d translation_ = Eigen::Vector3d::Zero();
  Eigen::Quaterniond rotation_ = Eigen::Quaterniond::Identity();
};

// Decoupled interpolation: translation linearly, rotation by spherical linear
// interpolation along the shorter arc. t = 0 gives a, t = 1 gives b.
inline Pose3 Interpolate(const Pose3& a, const Pose3& b, double t) {
  return {a.translation() + t * (b.translation() - a.translation()),
          a.rotation().slerp(t, b.rotation())};
}

// Rotation angle of `q` in [0, pi], insensitive to the sign of q.
inline double RotationAngle(const Eigen::Quaterniond& q) {
  return 2.0 * std::atan2(q.vec().norm(), std::abs(q.w()));
}

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_GRAPH_POSE3_H_
