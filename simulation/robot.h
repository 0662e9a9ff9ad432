// A differential-drive robot (a Pioneer 3DX by default) that drives routes
// through the office, and its wheel odometry.
//
// The robot follows each traversal's route (a polyline of waypoints, shifted
// sideways by the traversal's lateral offset) with a pure-pursuit controller:
// it cruises at the traversal's speed on straights and slows to
// `min_speed_m_s` in turns, with its turn rate limited. Its motion is
// integrated exactly (constant v and omega over each simulation step), so
// the ground truth has no integration error.
//
// Wheel odometry integrates the wheel travel measured over each odometry
// period: every wheel's travel is scaled by its systematic error (wheel
// radius) and perturbed by Gaussian noise whose variance grows with the
// distance the wheel rolled; the heading change uses a track width that is
// off by `track_error`. The odometry frame starts at the origin, as on a real
// robot, not at the true start pose.
#ifndef CATGRAPH_SIMULATION_ROBOT_H_
#define CATGRAPH_SIMULATION_ROBOT_H_

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "backend/io/dataset.h"

namespace catgraph {

struct RobotOptions {
  double track_m = 0.33;              // distance between the wheels (Pioneer 3DX); > 0
  double lookahead_m = 0.7;           // pure-pursuit lookahead; > 0
  double max_turn_rate_rad_s = 0.8;   // > 0
  double min_speed_m_s = 0.3;         // speed in the sharpest turns; (0, cruise speed]
};

struct OdometryOptions {
  double rate_hz = 10.0;                // odometry messages per second; > 0
  // Defaults give an end-point error of 1.4-3.7% of the distance after the
  // built-in 85 m loop (seeds 1-8; docs/simulation.md).
  double noise_m_per_sqrt_m = 0.001;    // std of a wheel's travel error per sqrt(metre rolled); >= 0
  double left_scale_error = 0.0015;     // measured / true travel - 1, left wheel; |e| < 0.5
  double right_scale_error = 0.0012;    // the same, right wheel
  double track_error = 0.01;            // assumed / true track width - 1; |e| < 0.5
};

struct TraversalPlan {
  int id = 1;                          // traversal id written with every frame; >= 1
  double speed_m_s = 0.4;              // cruise speed; > 0
  double lateral_offset_m = 0.0;       // the route shifted this far to the left
  std::vector<Eigen::Vector2d> route;  // waypoints, >= 2
};

struct RobotRun {
  std::vector<TimedPose2> truth;      // every simulation step, world frame
  std::vector<int> traversal;         // the traversal being driven, per step
  std::vector<TimedPose2> odometry;   // at OdometryOptions::rate_hz, odometry frame
  std::vector<double> traversal_end_s;  // when each traversal ended
  std::vector<double> distance_m;       // true distance driven in each traversal
};

// The route shifted sideways by `offset_m` (positive to the left of the
// direction of travel), corners mitred. Consecutive duplicate points are
// dropped. Throws std::invalid_argument with fewer than 2 distinct points.
std::vector<Eigen::Vector2d> OffsetRoute(const std::vector<Eigen::Vector2d>& route, double offset_m);

// The true poses at `times` (sorted, duplicates within 0.1 us dropped),
// interpolated between simulation steps. Throws std::out_of_range outside
// the run.
std::vector<TimedPose2> TruthAt(const RobotRun& run, std::vector<double> times);

// Throws std::invalid_argument unless rate_hz is in (0, 1000], the noise is
// >= 0 and the scale and track errors are below 0.5 in magnitude.
void Validate(const OdometryOptions& odometry);

// The wheel-odometry model of DriveRoutes along a given true path: each step's travel
// split onto two wheels `track_m` apart, measured with the scale, track and
// noise errors of `noise`, and integrated from the origin. One
// odometry pose per path pose; deterministic for a seed.
std::vector<TimedPose2> WheelOdometryAlong(const std::vector<TimedPose2>& path, double track_m,
                                           const OdometryOptions& noise, std::uint64_t seed);

// Drives the traversals one after the other, starting at the first
// waypoint facing the second. Throws std::invalid_argument on bad options
// and std::runtime_error when the controller cannot reach a route's end.
RobotRun DriveRoutes(const std::vector<TraversalPlan>& traversals, const RobotOptions& robot,
                     const OdometryOptions& odometry, std::uint64_t seed);

}  // namespace catgraph

#endif  // CATGRAPH_SIMULATION_ROBOT_H_
