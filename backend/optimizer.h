// Solving a FactorGraph with Ceres: Levenberg-Marquardt on a sparse normal
// Cholesky factorisation (SuiteSparse CHOLMOD).
#ifndef CATGRAPH_BACKEND_OPTIMIZER_H_
#define CATGRAPH_BACKEND_OPTIMIZER_H_

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <ceres/problem.h>

#include "backend/factor_graph.h"

namespace catgraph {

struct OptimizerOptions {
  int max_iterations = 200;            // Levenberg-Marquardt iterations; >= 1
  double function_tolerance = 1e-10;   // relative cost change that ends the solve; > 0
  double gradient_tolerance = 1e-12;   // max-norm of the projected gradient; > 0
  double parameter_tolerance = 1e-10;  // relative step size; > 0
  // Threads of the Jacobians' evaluation and of the factorisation's dense
  // kernels (OpenBLAS, CHOLMOD's OpenMP); >= 1
  int num_threads = 1;
  // A caller's test, run after every iteration that lowered the cost, on
  // the current values and that iteration's relative decrease |dF| / F.
  // When it returns true the solve ends there as converged (Ceres'
  // IterationCallback returning SOLVER_TERMINATE_SUCCESSFULLY). Unset: only
  // the tolerances and max_iterations end the solve.
  std::function<bool(const Values& values, double relative_decrease)> stop_test;
};

// Throws std::invalid_argument naming the first bad field.
void Validate(const OptimizerOptions& options);

enum class Termination { kNotRun, kConverged, kNoConvergence, kFailure };

struct Summary {
  Termination termination = Termination::kNotRun;
  std::string message = "Optimize() was not called.";
  int iterations = 0;
  double initial_cost = 0.0;  // Ceres' cost: half the sum of squared residuals
  double final_cost = 0.0;
  double time_s = 0.0;
  // Where time_s went (Ceres' own breakdown): forming and factoring the
  // linear systems, evaluating the Jacobians, evaluating the residuals.
  double preprocessor_time_s = 0.0;  // checks, orderings, the evaluator
  double linear_solver_time_s = 0.0;
  double jacobian_time_s = 0.0;
  double residual_time_s = 0.0;
  int residual_blocks = 0;
  int parameter_blocks = 0;
  bool stopped_by_test = false;  // OptimizerOptions::stop_test ended the solve

  // Converged, or stopped at the iteration limit with a finite cost.
  bool IsUsable() const;
  std::string BriefReport() const;
  // Adds `other`'s times (time_s and its breakdown) to these: the time of
  // several solves reported as one.
  void AddTimes(const Summary& other);
  // Sets these times to `other`'s.
  void SetTimes(const Summary& other);
};

struct OptimizationResult {
  Values values;
  Summary summary;
};

// Every key of every factor must be in `initial`; throws std::invalid_argument
// otherwise.
OptimizationResult Optimize(const FactorGraph& graph, const Values& initial,
                            const OptimizerOptions& options = {});

// A factor graph solved again and again as it grows, on one ceres::Problem
// that takes each variable and factor as it arrives (Optimize builds one per
// call): each Solve starts from the current values, and a factor removed or
// a variable held constant leaves the rest as it is. Ceres' own elimination
// order (Optimize may choose a dissection). For an online back end that
// solves after every few new poses. Thread-compatible.
//
//   IncrementalOptimizer optimizer(options);
//   optimizer.Insert(PoseId(0), Pose2());
//   optimizer.SetConstant(PoseKey(PoseId(0)));
//   for (each new pose and its factors) {
//     optimizer.Insert(id, guess);
//     const auto handle = optimizer.Add(std::make_unique<BetweenFactor<Pose2>>(...));
//     optimizer.Solve();
//   }
class IncrementalOptimizer {
 public:
  using FactorHandle = std::int64_t;

  // Throws std::invalid_argument on bad options.
  explicit IncrementalOptimizer(const OptimizerOptions& options = {});
  ~IncrementalOptimizer();
  IncrementalOptimizer(const IncrementalOptimizer&) = delete;
  IncrementalOptimizer& operator=(const IncrementalOptimizer&) = delete;

  // A new variable. Throws std::invalid_argument when its key has one.
  void Insert(PoseId id, const Pose2& pose) { InsertNew(PoseKey(id), [&] { values_.Insert(id, pose); }); }
  void Insert(PoseId id, const Pose3& pose) { InsertNew(PoseKey(id), [&] { values_.Insert(id, pose); }); }
  void Insert(SwitchId id, double value) { InsertNew(SwitchKey(id), [&] { values_.Insert(id, value); }); }
  // A switch's value set between solves. Throws std::out_of_range or
  // std::invalid_argument when `id` has no switch.
  void Set(SwitchId id, double value);

  // Adds `factor` over variables inserted before; the handle removes it.
  // Throws std::invalid_argument for a key without a value.
  FactorHandle Add(std::unique_ptr<Factor> factor);
  // Throws std::invalid_argument for a handle not (or no longer) added.
  void Remove(FactorHandle handle);
  // Holds `key`'s variable at its value in the solves that follow, or
  // frees it again.
  void SetConstant(Key key, bool constant = true);

  // Levenberg-Marquardt from the current values, as Optimize's.
  Summary Solve();

  const Values& values() const { return values_; }
  std::size_t num_factors() const { return factors_.size(); }

 private:
  void InsertNew(Key key, const std::function<void()>& insert);

  OptimizerOptions options_;
  Values values_;                            // node-based: the problem points into it
  std::unique_ptr<ceres::Problem> problem_;  // after values_: gone before it
  std::map<FactorHandle, ceres::ResidualBlockId> factors_;
  FactorHandle next_handle_ = 0;
};

// Tangent spaces. A variable's tangent space is the one the optimiser steps
// in: a Pose2's is its parameters (x, y, theta); a Pose3's is Ceres'
// ProductManifold<EuclideanManifold<3>, EigenQuaternionManifold>'s, 6 in
// all: the translation, then the rotation increment d applied on the left,
// q -> [cos|d|, sin|d| d/|d|] * q (a rotation by 2|d| in the world frame);
// a switch's is its value.

// GTSAM's Marginals, for pairs of variables: the joint covariance of `a` and
// `b` ([a; b] in their tangent spaces) of the Gaussian the factors define
// when linearised at `values` (robust losses ignored). Constant variables
// have zero covariance; variables no factor reaches are left out. Computed
// from one sparse Cholesky factorisation of the information sum J^T J and,
// per pair, a forward solve on the rows of the factor the pair's columns
// reach (their paths to the root of the elimination tree). Throws std::runtime_error when it does not
// exist (the information matrix is singular: no variable held constant, or
// one the factors do not determine); std::invalid_argument for a key that
// is not in `values` or that no factor reaches.
std::vector<Eigen::MatrixXd> JointMarginalCovariances(const FactorGraph& graph, const Values& values,
                                                      const std::vector<std::pair<Key, Key>>& pairs);

// A factor linearised at `values` (GTSAM's linearize): its residual, and its
// Jacobian with respect to each of its keys in their tangent spaces.
struct LinearizedFactor {
  Eigen::VectorXd residual;
  std::vector<Eigen::MatrixXd> jacobians;  // in the order of keys()
};
LinearizedFactor Linearize(const Factor& factor, const Values& values);

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_OPTIMIZER_H_
