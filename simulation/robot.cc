#include "simulation/robot.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>

#include "backend/graph/angle.h"

namespace catgraph {
namespace {

constexpr double kMinSimRateHz = 100.0;

// Arc-length parametrised polyline.
class Polyline {
 public:
  explicit Polyline(std::vector<Eigen::Vector2d> points) : points_(std::move(points)) {
    cumulative_.push_back(0.0);
    for (std::size_t i = 1; i < points_.size(); ++i) {
      cumulative_.push_back(cumulative_.back() + (points_[i] - points_[i - 1]).norm());
    }
  }
  double length() const { return cumulative_.back(); }
  Eigen::Vector2d At(double s) const {
    s = std::clamp(s, 0.0, length());
    const auto it = std::upper_bound(cumulative_.begin(), cumulative_.end(), s);
    const std::size_t i = std::min<std::size_t>(static_cast<std::size_t>(it - cumulative_.begin()),
                                                points_.size() - 1);
    const double span = cumulative_[i] - cumulative_[i - 1];
    const double t = span > 0.0 ? (s - cumulative_[i - 1]) / span : 0.0;
    return points_[i - 1] + t * (points_[i] - points_[i - 1]);
  }
  // The arc length of the point nearest to p among the segments overlapping
  // [s_min, s_max].
  double Project(const Eigen::Vector2d& p, double s_min, double s_max) const {
    double best_s = s_min, best_d = std::numeric_limits<double>::infinity();
    for (std::size_t i = 1; i < points_.size(); ++i) {
      if (cumulative_[i] < s_min || cumulative_[i - 1] > s_max) continue;
      const Eigen::Vector2d a = points_[i - 1], ab = points_[i] - a;
      const double len2 = ab.squaredNorm();
      double t = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
      double s = cumulative_[i - 1] + t * std::sqrt(len2);
      s = std::clamp(s, s_min, s_max);
      const double d = (At(s) - p).squaredNorm();
      if (d < best_d) best_d = d, best_s = s;
    }
    return best_s;
  }

 private:
  std::vector<Eigen::Vector2d> points_;
  std::vector<double> cumulative_;
};

// Exact motion at constant (v, omega) for dt, in the robot frame.
Pose2 Arc(double v, double omega, double dt) {
  const double a = omega * dt;
  if (std::abs(a) < 1e-9) return {v * dt, 0.0, a};
  return {v / omega * std::sin(a), v / omega * (1.0 - std::cos(a)), a};
}

// The robot's travel and turn since the last odometry message as its
// encoders measure the wheels' true travel `left` and `right`: each wheel's
// scale error and noise (two normal draws, the left wheel's first), and the
// track error.
std::pair<double, double> MeasuredTravel(double left, double right, double track_m, const OdometryOptions& odo,
                                         std::mt19937_64& rng, std::normal_distribution<double>& normal) {
  const double l = left * (1.0 + odo.left_scale_error) + odo.noise_m_per_sqrt_m * std::sqrt(std::abs(left)) * normal(rng);
  const double r =
      right * (1.0 + odo.right_scale_error) + odo.noise_m_per_sqrt_m * std::sqrt(std::abs(right)) * normal(rng);
  return {0.5 * (l + r), (r - l) / (track_m * (1.0 + odo.track_error))};
}

void Validate(const std::vector<TraversalPlan>& traversals, const RobotOptions& robot,
              const OdometryOptions& odometry) {
  if (traversals.empty()) throw std::invalid_argument("expected at least one traversal");
  if (!(robot.track_m > 0.0) || !(robot.lookahead_m > 0.0) || !(robot.max_turn_rate_rad_s > 0.0) ||
      !(robot.min_speed_m_s > 0.0)) {
    throw std::invalid_argument("robot: expected track_m, lookahead_m, max_turn_rate_rad_s and "
                                "min_speed_m_s > 0");
  }
  catgraph::Validate(odometry);
  for (const auto& t : traversals) {
    if (t.id < 1) throw std::invalid_argument("traversal ids start at 1; found " + std::to_string(t.id));
    if (!(t.speed_m_s >= robot.min_speed_m_s && t.speed_m_s <= 3.0)) {
      throw std::invalid_argument("traversal " + std::to_string(t.id) +
                                  ": expected speed_m_s between robot.min_speed_m_s and 3");
    }
  }
}

}  // namespace

void Validate(const OdometryOptions& odometry) {
  if (!(odometry.rate_hz > 0.0 && odometry.rate_hz <= 1000.0) || !(odometry.noise_m_per_sqrt_m >= 0.0) ||
      !(std::abs(odometry.left_scale_error) < 0.5) || !(std::abs(odometry.right_scale_error) < 0.5) ||
      !(std::abs(odometry.track_error) < 0.5)) {
    throw std::invalid_argument("odometry: expected rate_hz in (0, 1000], noise_m_per_sqrt_m >= 0 "
                                "and scale and track errors below 0.5 in magnitude");
  }
}

std::vector<Eigen::Vector2d> OffsetRoute(const std::vector<Eigen::Vector2d>& route, double offset_m) {
  std::vector<Eigen::Vector2d> p;
  for (const auto& q : route) {
    if (!q.allFinite()) throw std::invalid_argument("route: expected finite waypoints");
    if (p.empty() || (q - p.back()).norm() > 1e-9) p.push_back(q);
  }
  if (p.size() < 2) throw std::invalid_argument("route: expected at least 2 distinct waypoints");
  if (offset_m == 0.0) return p;
  std::vector<Eigen::Vector2d> normals;
  for (std::size_t i = 1; i < p.size(); ++i) {
    const Eigen::Vector2d d = (p[i] - p[i - 1]).normalized();
    normals.emplace_back(-d.y(), d.x());
  }
  std::vector<Eigen::Vector2d> out;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (i == 0) {
      out.push_back(p[i] + offset_m * normals.front());
    } else if (i + 1 == p.size()) {
      out.push_back(p[i] + offset_m * normals.back());
    } else {
      const Eigen::Vector2d& a = normals[i - 1];
      const Eigen::Vector2d& b = normals[i];
      const double denominator = 1.0 + a.dot(b);
      // A U-turn has no mitre; keep the corner's own offset.
      out.push_back(denominator > 1e-6 ? Eigen::Vector2d(p[i] + offset_m * (a + b) / denominator)
                                       : Eigen::Vector2d(p[i] + offset_m * a));
    }
  }
  return out;
}

std::vector<TimedPose2> TruthAt(const RobotRun& run, std::vector<double> times) {
  std::sort(times.begin(), times.end());
  std::vector<TimedPose2> truth;
  for (const double t : times) {
    if (!truth.empty() && t - truth.back().timestamp_s < 1e-7) continue;
    truth.push_back({t, InterpolatePose(run.truth, t)});
  }
  return truth;
}

RobotRun DriveRoutes(const std::vector<TraversalPlan>& traversals, const RobotOptions& robot,
                     const OdometryOptions& odo, std::uint64_t seed) {
  Validate(traversals, robot, odo);
  const int substeps = static_cast<int>(std::ceil(kMinSimRateHz / odo.rate_hz));
  const double dt = 1.0 / (odo.rate_hz * substeps);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);

  RobotRun run;
  const std::vector<Eigen::Vector2d> first = OffsetRoute(traversals.front().route,
                                                         traversals.front().lateral_offset_m);
  const Eigen::Vector2d heading = first[1] - first[0];
  Pose2 pose(first[0].x(), first[0].y(), std::atan2(heading.y(), heading.x()));
  Pose2 odometry_pose;
  double t = 0.0, left = 0.0, right = 0.0;
  int step = 0;
  run.truth.push_back({t, pose});
  run.traversal.push_back(traversals.front().id);
  run.odometry.push_back({t, odometry_pose});
  // One odometry message: the wheel travel since the last one, as measured,
  // integrated at the midpoint heading.
  auto tick = [&] {
    const auto [ds, dtheta] = MeasuredTravel(left, right, robot.track_m, odo, rng, normal);
    odometry_pose =
        odometry_pose * Pose2(ds * std::cos(0.5 * dtheta), ds * std::sin(0.5 * dtheta), dtheta);
    run.odometry.push_back({t, odometry_pose});
    left = right = 0.0;
  };

  for (const TraversalPlan& plan : traversals) {
    const Polyline route(OffsetRoute(plan.route, plan.lateral_offset_m));
    double s = route.Project(pose.translation(), 0.0, std::min(route.length(), 2.0));
    double distance = 0.0;
    const long max_steps = static_cast<long>(10.0 * (route.length() + 10.0) / robot.min_speed_m_s / dt);
    for (long k = 0;; ++k) {
      if (k > max_steps) {
        throw std::runtime_error("traversal " + std::to_string(plan.id) +
                                 ": the robot did not reach the end of its route (a waypoint it "
                                 "cannot turn to?)");
      }
      s = route.Project(pose.translation(), s - 0.2, s + 1.0);
      if (route.length() - s < 0.02) break;
      const Eigen::Vector2d target = route.At(s + robot.lookahead_m);
      const Eigen::Vector2d local = pose.rotation().transpose() * (target - pose.translation());
      const double alpha = std::atan2(local.y(), local.x());
      const double reach = std::max(local.norm(), 0.05);
      const double c = std::max(0.0, std::cos(alpha));
      const double v = robot.min_speed_m_s + (plan.speed_m_s - robot.min_speed_m_s) * c * c * c * c;
      const double omega = std::clamp(2.0 * v * std::sin(alpha) / reach, -robot.max_turn_rate_rad_s,
                                      robot.max_turn_rate_rad_s);
      pose = pose * Arc(v, omega, dt);
      left += (v - 0.5 * omega * robot.track_m) * dt;
      right += (v + 0.5 * omega * robot.track_m) * dt;
      distance += v * dt;
      t = (++step) * dt;
      run.truth.push_back({t, pose});
      run.traversal.push_back(plan.id);
      if (step % substeps == 0) tick();
    }
    run.traversal_end_s.push_back(t);
    run.distance_m.push_back(distance);
  }
  // Stand still until the next odometry message, so that every frame lies
  // inside the odometry's time range.
  while (step % substeps != 0) {
    t = (++step) * dt;
    run.truth.push_back({t, pose});
    run.traversal.push_back(traversals.back().id);
    if (step % substeps == 0) tick();
  }
  return run;
}

std::vector<TimedPose2> WheelOdometryAlong(const std::vector<TimedPose2>& path, double track_m,
                                           const OdometryOptions& noise, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<TimedPose2> out;
  if (path.empty()) return out;
  Pose2 pose;
  out.push_back({path.front().timestamp_s, pose});
  for (std::size_t i = 1; i < path.size(); ++i) {
    const Pose2 d = path[i - 1].pose.Between(path[i].pose);
    const double chord = std::hypot(d.x(), d.y());
    // The chord's direction in the robot's frame (half the turn for a wheeled
    // robot's arc); travel is backwards when it points behind the arc's mean
    // heading, and its length is then negative.
    const double direction = chord > 0.0 ? std::atan2(d.y(), d.x()) : 0.5 * d.theta();
    const bool backwards = std::abs(WrapAngle(direction - 0.5 * d.theta())) > 0.5 * std::numbers::pi;
    const double travel_direction = backwards ? direction - std::numbers::pi : direction;
    const double ds = backwards ? -chord : chord;
    const double left = ds - 0.5 * d.theta() * track_m, right = ds + 0.5 * d.theta() * track_m;
    const auto [measured_ds, measured_dtheta] = MeasuredTravel(left, right, track_m, noise, rng, normal);
    // Along the direction of travel, turned by half the turn's error.
    const double heading = travel_direction + 0.5 * (measured_dtheta - d.theta());
    pose = pose * Pose2(measured_ds * std::cos(heading), measured_ds * std::sin(heading), measured_dtheta);
    out.push_back({path[i].timestamp_s, pose});
  }
  return out;
}

}  // namespace catgraph
