// Angle helpers shared by every layer.
#ifndef CATGRAPH_BACKEND_GRAPH_ANGLE_H_
#define CATGRAPH_BACKEND_GRAPH_ANGLE_H_

#include <cmath>
#include <numbers>

namespace catgraph {

// Maps any finite angle to (-pi, pi]. +pi stays +pi and -pi maps to +pi, so an
// angle and its wrap always describe the same rotation and the interval is
// half-open exactly as in g2o's normalize_theta.
inline double WrapAngle(double angle_rad) {
  // Most angles are in range already; std::remainder costs tens of ns, and
  // the particle filters wrap millions of angles (returns the same value).
  if (angle_rad > -std::numbers::pi && angle_rad <= std::numbers::pi) return angle_rad;
  double wrapped = std::remainder(angle_rad, 2.0 * std::numbers::pi);  // [-pi, pi]
  if (wrapped <= -std::numbers::pi) wrapped += 2.0 * std::numbers::pi;
  return wrapped;
}

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_GRAPH_ANGLE_H_
