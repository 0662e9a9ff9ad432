// A Manhattan-world pose graph with exact ground truth, in the spirit of
// Olson's M3500: the robot walks a grid, turning at random, and every return
// to a grid point it has visited before may yield a loop closure.
//
// Odometry and loop closures are the true relative poses perturbed by
// Gaussian noise of the stated covariance, and carry that covariance's
// inverse as information, so the graph is statistically consistent. The
// initial guess is the chained noisy odometry. The same options and seed give
// the same graph, bit for bit.
#ifndef CATGRAPH_SIMULATION_MANHATTAN_WORLD_H_
#define CATGRAPH_SIMULATION_MANHATTAN_WORLD_H_

#include <cstdint>

#include "backend/graph/pose_graph.h"

namespace catgraph {

// The most poses a generated world has, and the most edges it is expected
// to have (ExpectedManhattanEdges): on a fixed grid its closures grow with
// the square of the poses, and each edge takes about 560 bytes while the
// world is built (50,000 poses on the default grid: 5.7 million edges,
// 3.2 GB; BENCHMARKS.md).
inline constexpr int kMaxManhattanPoses = 1'000'000;
inline constexpr double kMaxManhattanEdges = 6.5e6;

struct ManhattanWorldOptions {
  int num_poses = 500;                      // >= 2
  double grid_step_m = 1.0;                 // distance between grid points; > 0
  int grid_cells = 10;                      // the walk stays in a square of this many steps; >= 2
  double turn_probability = 0.3;            // chance of turning left or right at a grid point; [0, 1]
  double closure_probability = 0.5;         // chance that a revisit yields a closure; [0, 1]
  int min_closure_separation = 10;          // closures only between poses this many steps apart; >= 2
  double odometry_sigma_m = 0.05;           // translation noise per step, each axis; > 0
  double odometry_sigma_rad = 0.01;         // heading noise per step; > 0
  double closure_sigma_m = 0.05;            // translation noise of a loop closure; > 0
  double closure_sigma_rad = 0.01;          // heading noise of a loop closure; > 0
  std::uint64_t seed = 1;
};

// Throws std::invalid_argument naming the first offending field, or the
// expected edges when they exceed kMaxManhattanEdges.
void Validate(const ManhattanWorldOptions& options);

// The edges a world is expected to have: the odometry, and the closures of
// a walk that visits each of the grid's c^2 points N / c^2 times, p N^2 /
// (2 c^2) for N poses and closure probability p (within 11 % of the
// generated count from 10,000 to 50,000 poses on 10- and 50-step squares).
double ExpectedManhattanEdges(const ManhattanWorldOptions& options);

struct SimulatedPoseGraph2 {
  PoseGraph2 graph;  // noisy measurements, chained-odometry initial guess
  PoseGraph2 truth;  // the same edges with exact measurements, true poses
};

SimulatedPoseGraph2 SimulateManhattanWorld(const ManhattanWorldOptions& options);

}  // namespace catgraph

#endif  // CATGRAPH_SIMULATION_MANHATTAN_WORLD_H_
