#include "backend/optimizer.h"

#include <dlfcn.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <ceres/ceres.h>

#include "backend/elimination_ordering.h"

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

namespace {

using Pose3Manifold = ceres::ProductManifold<ceres::EuclideanManifold<3>, ceres::EigenQuaternionManifold>;

// `key`'s block of `values` as a parameter block of `problem`.
void AddVariable(Values& values, Key key, ceres::Problem& problem) {
  const VariableKind kind = values.KindOf(key);
  double* block = values.MutableBlock(key);
  if (kind == VariableKind::kPose3) {
    problem.AddParameterBlock(block, 7, new Pose3Manifold());
  } else {
    problem.AddParameterBlock(block, Values::BlockSize(kind));
  }
}

// `factor` over `values`' blocks as a residual block of `problem`, with its
// robust loss and bounds; `who` names the caller in the error for a key
// without a value.
ceres::ResidualBlockId AddFactor(const Factor& factor, Values& values, ceres::Problem& problem, const char* who) {
  std::vector<double*> blocks;
  for (const Key key : factor.keys()) {
    if (!values.Contains(key)) {
      throw std::invalid_argument(std::string(who) + ": a factor uses " + ToString(key) + ", which has no initial value");
    }
    blocks.push_back(values.MutableBlock(key));
  }
  const ceres::ResidualBlockId id =
      problem.AddResidualBlock(factor.NewCostFunction().release(), factor.NewLossFunction().release(), blocks);
  for (const ParameterBound& b : factor.bounds()) {
    double* block = values.MutableBlock(b.key);
    problem.SetParameterLowerBound(block, b.index, b.lower);
    problem.SetParameterUpperBound(block, b.index, b.upper);
  }
  return id;
}

// The factors over `values`' blocks as a ceres::Problem (which keeps
// pointers into `values`), with their robust losses and bounds.
void BuildProblem(const FactorGraph& graph, Values& values, ceres::Problem& problem) {
  for (const Key key : values.keys()) AddVariable(values, key, problem);
  for (const auto& factor : graph.factors()) AddFactor(*factor, values, problem, "Optimize");
  for (const Key key : graph.constant_keys()) {
    if (values.Contains(key)) problem.SetParameterBlockConstant(values.MutableBlock(key));
  }
}

// The threads of the factorisation's dense kernels, for one solve: the
// solve's num_threads for OpenBLAS (which would otherwise start one per
// core), and with one thread none for OpenMP (CHOLMOD's supernodal step
// asks it for four whatever the machine, which on two cores cost a fifth
// of a large solve's time in switching; BENCHMARKS.md). One thread leaves
// the other cores to the caller. Both settings are process-wide, so they
// are restored afterwards; found at run time, so that a BLAS or an OpenMP
// other than these is left as it is.
class DenseKernelThreads {
 public:
  explicit DenseKernelThreads(int threads) {
    if (set_blas_ && get_blas_) {
      blas_before_ = get_blas_();
      set_blas_(threads);
    }
    if (threads == 1 && set_levels_ && get_levels_) {
      levels_before_ = get_levels_();
      set_levels_(0);
    }
  }
  ~DenseKernelThreads() {
    if (blas_before_ > 0) set_blas_(blas_before_);
    if (levels_before_ >= 0) set_levels_(levels_before_);
  }
  DenseKernelThreads(const DenseKernelThreads&) = delete;
  DenseKernelThreads& operator=(const DenseKernelThreads&) = delete;

 private:
  using SetInt = void(int);
  using GetInt = int();
  template <typename F>
  static F* Find(const char* name) {
    return reinterpret_cast<F*>(dlsym(RTLD_DEFAULT, name));
  }
  inline static SetInt* const set_blas_ = Find<SetInt>("openblas_set_num_threads");
  inline static GetInt* const get_blas_ = Find<GetInt>("openblas_get_num_threads");
  inline static SetInt* const set_levels_ = Find<SetInt>("omp_set_max_active_levels");
  inline static GetInt* const get_levels_ = Find<GetInt>("omp_get_max_active_levels");
  int blas_before_ = 0;
  int levels_before_ = -1;
};

// FillReducingOrder as Ceres' ordering: a group per variable, in order, and
// the blocks held constant or read by no factor last (Ceres wants every
// block listed). Null where Ceres keeps its own.
std::shared_ptr<ceres::ParameterBlockOrdering> CeresOrdering(const FactorGraph& graph, Values& values) {
  const std::vector<Key> order = FillReducingOrder(graph, values);
  if (order.empty()) return nullptr;
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  for (const Key key : order) ordering->AddElementToGroup(values.MutableBlock(key), ordering->NumGroups());
  const int last = ordering->NumGroups();
  for (const Key key : values.keys()) {
    double* block = values.MutableBlock(key);
    if (!ordering->IsMember(block)) ordering->AddElementToGroup(block, last);
  }
  return ordering;
}

// `removable`: residual blocks are removed one by one (IncrementalOptimizer),
// which Ceres makes cheap at the cost of a little memory per block.
ceres::Problem::Options ProblemOptions(bool removable = false) {
  ceres::Problem::Options options;
  // The Problem owns cost and loss functions (the documented hand-off) and
  // manifolds, which BuildProblem creates per block.
  options.manifold_ownership = ceres::TAKE_OWNERSHIP;
  options.enable_fast_removal = removable;
  return options;
}

// OptimizerOptions::stop_test as a Ceres callback; the values are current
// because the solver updates them every iteration.
class StopTestCallback : public ceres::IterationCallback {
 public:
  StopTestCallback(const OptimizerOptions& options, const Values& values)
      : test_(options.stop_test), values_(values) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    if (s.iteration == 0 || !s.step_is_successful || s.cost <= 0.0) return ceres::SOLVER_CONTINUE;
    if (!test_(values_, std::abs(s.cost_change) / s.cost)) return ceres::SOLVER_CONTINUE;
    stopped_ = true;
    return ceres::SOLVER_TERMINATE_SUCCESSFULLY;
  }
  bool stopped() const { return stopped_; }

 private:
  const std::function<bool(const Values&, double)>& test_;
  const Values& values_;
  bool stopped_ = false;
};

// Levenberg-Marquardt on `problem`, whose blocks are `values`', with
// `ordering` (null: Ceres' own); `ordering_s`, the time it took, counts as
// preprocessing. Leaves 2D headings wrapped.
Summary SolveProblem(ceres::Problem& problem, Values& values, const OptimizerOptions& options,
                     std::shared_ptr<ceres::ParameterBlockOrdering> ordering, double ordering_s) {
  ceres::Solver::Options solver;
  solver.minimizer_type = ceres::TRUST_REGION;
  solver.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  solver.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  solver.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  solver.linear_solver_ordering = std::move(ordering);
  solver.max_num_iterations = options.max_iterations;
  solver.function_tolerance = options.function_tolerance;
  solver.gradient_tolerance = options.gradient_tolerance;
  solver.parameter_tolerance = options.parameter_tolerance;
  solver.num_threads = options.num_threads;
  solver.logging_type = ceres::SILENT;
  solver.minimizer_progress_to_stdout = false;

  StopTestCallback stop_test(options, values);
  if (options.stop_test) {
    solver.update_state_every_iteration = true;
    solver.callbacks.push_back(&stop_test);
  }

  ceres::Solver::Summary ceres_summary;
  {
    const DenseKernelThreads threads(options.num_threads);
    ceres::Solve(solver, &problem, &ceres_summary);
  }

  Summary s;
  switch (ceres_summary.termination_type) {
    case ceres::CONVERGENCE: s.termination = Termination::kConverged; break;
    case ceres::NO_CONVERGENCE: s.termination = Termination::kNoConvergence; break;
    case ceres::USER_SUCCESS: s.termination = Termination::kConverged; break;
    default: s.termination = Termination::kFailure; break;
  }
  s.stopped_by_test = stop_test.stopped();
  s.message = s.stopped_by_test ? "The caller's stop test ended the solve." : ceres_summary.message;
  s.iterations = static_cast<int>(ceres_summary.iterations.size()) - 1;
  s.initial_cost = ceres_summary.initial_cost;
  s.final_cost = ceres_summary.final_cost;
  // Ceres leaves a time at -1 when its stage did not run.
  // The elimination order is part of the preprocessing, computed before
  // Ceres' own.
  s.time_s = ordering_s + std::max(0.0, ceres_summary.total_time_in_seconds);
  s.preprocessor_time_s = ordering_s + std::max(0.0, ceres_summary.preprocessor_time_in_seconds);
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
  return s;
}

}  // namespace

OptimizationResult Optimize(const FactorGraph& graph, const Values& initial,
                            const OptimizerOptions& options) {
  Validate(options);
  OptimizationResult result{initial, {}};
  Values& values = result.values;
  ceres::Problem problem(ProblemOptions());
  BuildProblem(graph, values, problem);
  const auto ordering_start = std::chrono::steady_clock::now();
  std::shared_ptr<ceres::ParameterBlockOrdering> ordering = CeresOrdering(graph, values);
  const double ordering_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - ordering_start).count();
  result.summary = SolveProblem(problem, values, options, std::move(ordering), ordering_s);
  return result;
}

IncrementalOptimizer::IncrementalOptimizer(const OptimizerOptions& options)
    : options_(options), problem_(std::make_unique<ceres::Problem>(ProblemOptions(true))) {
  Validate(options_);
}

IncrementalOptimizer::~IncrementalOptimizer() = default;

void IncrementalOptimizer::InsertNew(Key key, const std::function<void()>& insert) {
  if (values_.Contains(key)) throw std::invalid_argument("IncrementalOptimizer: " + ToString(key) + " has a value");
  insert();
  AddVariable(values_, key, *problem_);
}

void IncrementalOptimizer::Set(SwitchId id, double value) {
  values_.AtSwitch(id);  // throws unless a switch
  values_.Insert(id, value);  // in place: the block stays where the problem has it
}

IncrementalOptimizer::FactorHandle IncrementalOptimizer::Add(std::unique_ptr<Factor> factor) {
  factors_.emplace(next_handle_, AddFactor(*factor, values_, *problem_, "IncrementalOptimizer"));
  return next_handle_++;
}

void IncrementalOptimizer::Remove(FactorHandle handle) {
  const auto found = factors_.find(handle);
  if (found == factors_.end()) throw std::invalid_argument("IncrementalOptimizer: no factor " + std::to_string(handle));
  problem_->RemoveResidualBlock(found->second);
  factors_.erase(found);
}

void IncrementalOptimizer::SetConstant(Key key, bool constant) {
  double* block = values_.MutableBlock(key);
  if (constant) {
    problem_->SetParameterBlockConstant(block);
  } else {
    problem_->SetParameterBlockVariable(block);
  }
}

Summary IncrementalOptimizer::Solve() {
  return SolveProblem(*problem_, values_, options_, nullptr, 0.0);
}

std::vector<Eigen::MatrixXd> JointMarginalCovariances(const FactorGraph& graph, const Values& values,
                                                      const std::vector<std::pair<Key, Key>>& pairs) {
  // The information H = sum J^T J over the factors, in the tangent spaces of
  // the variables not held constant; column offsets by key.
  std::set<Key> reached;
  for (const auto& factor : graph.factors()) {
    for (const Key key : factor->keys()) reached.insert(key);
  }
  std::map<Key, int> offset;
  int n = 0;
  for (const Key key : reached) {
    if (!values.Contains(key)) {
      throw std::invalid_argument("JointMarginalCovariances: no value for " + ToString(key));
    }
    if (graph.constant_keys().contains(key)) continue;
    offset.emplace(key, n);
    n += Values::TangentSize(values.KindOf(key));
  }
  for (const auto& [a, b] : pairs) {
    for (const Key key : {a, b}) {
      if (!reached.contains(key)) {
        throw std::invalid_argument("JointMarginalCovariances: no factor reaches " + ToString(key));
      }
    }
  }
  std::vector<Eigen::Triplet<double>> triplets;
  for (const auto& factor : graph.factors()) {
    const std::vector<Key> keys = factor->keys();
    const LinearizedFactor linear = Linearize(*factor, values);
    for (std::size_t i = 0; i < keys.size(); ++i) {
      const auto row = offset.find(keys[i]);
      if (row == offset.end()) continue;
      for (std::size_t j = 0; j < keys.size(); ++j) {
        const auto col = offset.find(keys[j]);
        if (col == offset.end() || col->second > row->second) continue;  // lower triangle
        const Eigen::MatrixXd block = linear.jacobians[i].transpose() * linear.jacobians[j];
        for (int r = 0; r < block.rows(); ++r) {
          for (int c = 0; c < block.cols(); ++c) {
            const int at_row = row->second + r, at_col = col->second + c;
            if (at_row >= at_col) triplets.emplace_back(at_row, at_col, block(r, c));
          }
        }
      }
    }
  }
  Eigen::SparseMatrix<double> information(n, n);
  information.setFromTriplets(triplets.begin(), triplets.end());
  // P H P^T = L L^T. A pivot that is a vanishing share of its diagonal
  // entry means H is singular (a gauge freedom: nothing held constant).
  const Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower> llt(information);
  bool singular = llt.info() != Eigen::Success;
  if (!singular) {
    const Eigen::VectorXd pivots = llt.matrixL().nestedExpression().diagonal();
    const Eigen::VectorXd diagonal = llt.permutationP() * Eigen::VectorXd(information.diagonal());
    for (int k = 0; k < n && !singular; ++k) singular = !(pivots(k) * pivots(k) > 1e-12 * diagonal(k));
  }
  if (singular) {
    throw std::runtime_error("JointMarginalCovariances: the information matrix is singular "
                             "(no variable held constant, or one the factors do not determine)");
  }
  // The joint covariance of (a, b) is E^T H^-1 E = Y^T Y for the columns E
  // of the identity at a and b and Y = L^-1 P E. A column of L has its
  // nonzeros only at ancestors of its own index in the elimination tree, so
  // Y is nonzero only on the union of the tree paths from a's and b's
  // columns to the root: the forward solve runs on those rows alone, at a
  // cost of the factor's entries in their columns (not of n per column, as
  // a general sparse solve would).
  const Eigen::SparseMatrix<double>& factor = llt.matrixL().nestedExpression();
  std::vector<int> parent(n, -1);  // the elimination tree
  for (int j = 0; j < n; ++j) {
    Eigen::SparseMatrix<double>::InnerIterator entry(factor, j);
    if (!entry || entry.row() != j) {
      throw std::logic_error("JointMarginalCovariances: the factor's diagonal is not stored first");
    }
    if (++entry) parent[j] = static_cast<int>(entry.row());
  }
  std::vector<int> local(n, -1);  // row of `y` of each row of the factor on the paths
  std::vector<int> path;
  std::vector<Eigen::MatrixXd> out;
  for (const auto& [a, b] : pairs) {
    const int na = Values::TangentSize(values.KindOf(a)), nb = Values::TangentSize(values.KindOf(b));
    Eigen::MatrixXd joint = Eigen::MatrixXd::Zero(na + nb, na + nb);
    std::vector<int> starts;  // permuted row of each free tangent coordinate
    std::vector<int> free;    // its row in `joint`
    for (const auto& [key, first, size] : {std::tuple{a, 0, na}, std::tuple{b, na, nb}}) {
      const auto found = offset.find(key);
      if (found == offset.end()) continue;  // held constant: zero covariance
      for (int k = 0; k < size; ++k) {
        starts.push_back(llt.permutationP().indices()(found->second + k));
        free.push_back(first + k);
      }
    }
    if (free.empty()) {
      out.push_back(std::move(joint));
      continue;
    }
    path.clear();
    for (const int start : starts) {
      for (int j = start; j != -1 && local[j] == -1; j = parent[j]) {
        local[j] = 0;
        path.push_back(j);
      }
    }
    std::sort(path.begin(), path.end());  // ancestors have higher indices
    for (std::size_t r = 0; r < path.size(); ++r) local[path[r]] = static_cast<int>(r);
    using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    RowMajorMatrix y = RowMajorMatrix::Zero(static_cast<Eigen::Index>(path.size()),
                                            static_cast<Eigen::Index>(free.size()));
    for (std::size_t c = 0; c < starts.size(); ++c) y(local[starts[c]], static_cast<Eigen::Index>(c)) = 1.0;
    for (const int j : path) {
      Eigen::SparseMatrix<double>::InnerIterator entry(factor, j);
      y.row(local[j]) /= entry.value();  // the diagonal, stored first
      for (++entry; entry; ++entry) y.row(local[entry.row()]) -= entry.value() * y.row(local[j]);
    }
    for (const int j : path) local[j] = -1;
    const Eigen::MatrixXd cov = y.transpose() * y;
    for (std::size_t r = 0; r < free.size(); ++r) {
      for (std::size_t c = 0; c < free.size(); ++c) joint(free[r], free[c]) = cov(r, c);
    }
    out.push_back(std::move(joint));
  }
  return out;
}

LinearizedFactor Linearize(const Factor& factor, const Values& values) {
  const std::unique_ptr<ceres::CostFunction> cost = factor.NewCostFunction();
  const std::vector<Key> keys = factor.keys();
  std::vector<const double*> parameters;
  std::vector<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> ambient;
  for (const Key key : keys) {
    if (!values.Contains(key)) throw std::invalid_argument("Linearize: no value for " + ToString(key));
    parameters.push_back(values.Block(key));
    ambient.emplace_back(cost->num_residuals(), Values::BlockSize(values.KindOf(key)));
  }
  std::vector<double*> jacobians;
  for (auto& j : ambient) jacobians.push_back(j.data());
  LinearizedFactor out;
  out.residual.resize(cost->num_residuals());
  if (!cost->Evaluate(parameters.data(), out.residual.data(), jacobians.data())) {
    throw std::runtime_error("Linearize: the factor could not be evaluated");
  }
  for (std::size_t i = 0; i < keys.size(); ++i) {
    if (values.KindOf(keys[i]) != VariableKind::kPose3) {
      out.jacobians.emplace_back(ambient[i]);
      continue;
    }
    Eigen::Matrix<double, 7, 6, Eigen::RowMajor> plus;
    Pose3Manifold().PlusJacobian(parameters[i], plus.data());
    out.jacobians.emplace_back(ambient[i] * plus);
  }
  return out;
}

}  // namespace catgraph
