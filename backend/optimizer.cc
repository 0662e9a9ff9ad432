#include "backend/optimizer.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <ceres/ceres.h>

namespace catgraph {
namespace {

void Require(bool ok, const char* field) {
  if (!ok) throw std::invalid_argument(std::string("OptimizerOptions::") + field + " is out of range");
}

}  // namespace

void Validate(const OptimizerOptions& o) {
  Require(o.max_iterations >= 1, "max_iterations");
  Require(o.function_tolerance > 0.0, "function_tolerance");
  Require(o.gradient_tolerance > 0.0, "gradient_tolerance");
  Require(o.parameter_tolerance > 0.0, "parameter_tolerance");
  Require(o.num_threads >= 1, "num_threads");
}

bool Summary::IsUsable() const {
  return (termination == Termination::kConverged || termination == Termination::kNoConvergence) &&
         std::isfinite(final_cost);
}

std::string Summary::BriefReport() const {
  static const char* kNames[] = {"not run", "converged", "no convergence", "failure"};
  std::ostringstream out;
  out << kNames[static_cast<int>(termination)] << ": " << iterations << " iterations, cost "
      << initial_cost << " -> " << final_cost << ", " << time_s << " s (" << message << ")";
  return out.str();
}

namespace {

constexpr double Summary::*kTimes[] = {&Summary::time_s, &Summary::preprocessor_time_s,
                                       &Summary::linear_solver_time_s, &Summary::jacobian_time_s,
                                       &Summary::residual_time_s};

}  // namespace

void Summary::AddTimes(const Summary& other) {
  for (const auto field : kTimes) this->*field += other.*field;
}

void Summary::SetTimes(const Summary& other) {
  for (const auto field : kTimes) this->*field = other.*field;
}

OptimizationResult Optimize(const FactorGraph& graph, const Values& initial,
                            const OptimizerOptions& options) {
  Validate(options);
  OptimizationResult result{initial, {}};
  Values& values = result.values;

  ceres::Problem::Options problem_options;
  // The Problem owns cost and loss functions (the documented hand-off) and
  // manifolds, which we create per block below.
  problem_options.manifold_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);

  for (const Key key : values.keys()) {
    const VariableKind kind = values.KindOf(key);
    double* block = values.MutableBlock(key);
    if (kind == VariableKind::kPose3) {
      problem.AddParameterBlock(
          block, 7,
          new ceres::ProductManifold<ceres::EuclideanManifold<3>, ceres::EigenQuaternionManifold>());
    } else {
      problem.AddParameterBlock(block, Values::BlockSize(kind));
    }
  }
  for (const auto& factor : graph.factors()) {
    std::vector<double*> blocks;
    for (const Key key : factor->keys()) {
      if (!values.Contains(key)) {
        throw std::invalid_argument("Optimize: a factor uses " + ToString(key) +
                                    ", which has no initial value");
      }
      blocks.push_back(values.MutableBlock(key));
    }
    problem.AddResidualBlock(factor->NewCostFunction().release(),
                             factor->NewLossFunction().release(), blocks);
    for (const ParameterBound& b : factor->bounds()) {
      double* block = values.MutableBlock(b.key);
      problem.SetParameterLowerBound(block, b.index, b.lower);
      problem.SetParameterUpperBound(block, b.index, b.upper);
    }
  }
  for (const Key key : graph.constant_keys()) {
    if (values.Contains(key) && problem.HasParameterBlock(values.MutableBlock(key))) {
      problem.SetParameterBlockConstant(values.MutableBlock(key));
    }
  }

  ceres::Solver::Options solver;
  solver.minimizer_type = ceres::TRUST_REGION;
  solver.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  solver.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  solver.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  solver.max_num_iterations = options.max_iterations;
  solver.function_tolerance = options.function_tolerance;
  solver.gradient_tolerance = options.gradient_tolerance;
  solver.parameter_tolerance = options.parameter_tolerance;
  solver.num_threads = options.num_threads;
  solver.logging_type = ceres::SILENT;
  solver.minimizer_progress_to_stdout = false;

  ceres::Solver::Summary ceres_summary;
  ceres::Solve(solver, &problem, &ceres_summary);

  Summary& s = result.summary;
  switch (ceres_summary.termination_type) {
    case ceres::CONVERGENCE: s.termination = Termination::kConverged; break;
    case ceres::NO_CONVERGENCE: s.termination = Termination::kNoConvergence; break;
    default: s.termination = Termination::kFailure; break;
  }
  s.message = ceres_summary.message;
  s.iterations = static_cast<int>(ceres_summary.iterations.size()) - 1;
  s.initial_cost = ceres_summary.initial_cost;
  s.final_cost = ceres_summary.final_cost;
  // Ceres leaves a time at -1 when its stage did not run.
  s.time_s = std::max(0.0, ceres_summary.total_time_in_seconds);
  s.preprocessor_time_s = std::max(0.0, ceres_summary.preprocessor_time_in_seconds);
  s.linear_solver_time_s = std::max(0.0, ceres_summary.linear_solver_time_in_seconds);
  s.jacobian_time_s = std::max(0.0, ceres_summary.jacobian_evaluation_time_in_seconds);
  s.residual_time_s = std::max(0.0, ceres_summary.residual_evaluation_time_in_seconds);
  s.residual_blocks = ceres_summary.num_residual_blocks;
  s.parameter_blocks = ceres_summary.num_parameter_blocks;
  // Keep 2D headings wrapped.
  for (const Key key : values.keys()) {
    if (values.KindOf(key) == VariableKind::kPose2) {
      double* block = values.MutableBlock(key);
      block[2] = WrapAngle(block[2]);
    }
  }
  return result;
}

}  // namespace catgraph
