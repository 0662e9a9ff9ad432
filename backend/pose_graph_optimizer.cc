#include "backend/pose_graph_optimizer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <variant>

#include "backend/chi_square.h"
#include "backend/graph/name_table.h"
#include "backend/graph/relative_pose_error.h"
#include "backend/initialization.h"
#include "backend/robust_losses.h"
#include "backend/robust_solve.h"

namespace catgraph {
namespace {

constexpr NameTable<RobustMethod, 6> kMethodNames = {{
    {RobustMethod::kNone, "none"},
    {RobustMethod::kSwitchable, "switchable"},
    {RobustMethod::kDcs, "dcs"},
    {RobustMethod::kCauchy, "cauchy"},
    {RobustMethod::kHuber, "huber"},
    {RobustMethod::kGnc, "gnc"},
}};

template <typename PoseT>
double EdgeChi2(const PoseGraph<PoseT>& graph, const Constraint<PoseT>& c) {
  return RelativePoseChi2(*graph.vertices.at(c.from).pose, *graph.vertices.at(c.to).pose, c.measurement);
}

template <typename PoseT>
double GraphChi2(const PoseGraph<PoseT>& graph) {
  double chi2 = 0.0;
  for (const auto& c : graph.constraints) {
    double scale = 1.0;
    if (c.switch_id) scale = std::pow(graph.switches.at(*c.switch_id).value, 2);
    chi2 += scale * EdgeChi2(graph, c);
  }
  for (const auto& [id, s] : graph.switches) {
    if (s.prior) chi2 += s.prior->information * std::pow(s.prior->mean - s.value, 2);
  }
  return chi2;
}

Eigen::Matrix2d RotationMatrixOf(const Pose2& p) { return p.rotation(); }
Eigen::Matrix3d RotationMatrixOf(const Pose3& p) { return p.rotation().toRotationMatrix(); }

// SE-Sync's chordal cost of one constraint (cost_functors.h's ChordalResidual).
template <typename PoseT>
double EdgeChordalCost(const PoseGraph<PoseT>& graph, const Constraint<PoseT>& c) {
  const PoseT& xi = *graph.vertices.at(c.from).pose;
  const PoseT& xj = *graph.vertices.at(c.to).pose;
  const auto w = ChordalWeightsOf<PoseT::kTangentDim>(c.measurement.information);
  const auto ri = RotationMatrixOf(xi);
  return w.kappa * (RotationMatrixOf(xj) - ri * RotationMatrixOf(c.measurement.mean)).squaredNorm() +
         w.tau * (xj.translation() - xi.translation() - ri * c.measurement.mean.translation()).squaredNorm();
}

// A constraint's squared residual norm in the objective `cost`: what the
// robust methods weigh and the gate is a quantile of.
template <typename PoseT>
double EdgeCost(const PoseGraph<PoseT>& graph, const Constraint<PoseT>& c, RelativePoseCostType cost) {
  return cost == RelativePoseCostType::kChordal ? EdgeChordalCost(graph, c) : EdgeChi2(graph, c);
}

template <typename PoseT>
double GraphChordalCost(const PoseGraph<PoseT>& graph) {
  double f = 0.0;
  for (const auto& c : graph.constraints) f += EdgeChordalCost(graph, c);
  return f;
}

}  // namespace

template <typename PoseT>
double Gate(RelativePoseCostType cost, double probability) {
  if (cost == RelativePoseCostType::kChordal) {
    return ChordalCostQuantile(std::is_same_v<PoseT, Pose2> ? 2 : 3, probability);
  }
  return ChiSquareQuantile(PoseT::kTangentDim, probability);
}

template double Gate<Pose2>(RelativePoseCostType, double);
template double Gate<Pose3>(RelativePoseCostType, double);

namespace {

// Whether the method decides at the gate, with no explicit parameter in its
// place.
bool DecidesAtGate(const PoseGraphOptimizerOptions& o) {
  switch (o.method) {
    case RobustMethod::kNone: return false;
    case RobustMethod::kSwitchable: return o.switch_prior_information == 0.0;
    case RobustMethod::kDcs: return o.dcs_phi == 0.0;
    case RobustMethod::kCauchy:
    case RobustMethod::kHuber: return o.loss_scale_sigma == 0.0;
    case RobustMethod::kGnc: return true;
  }
  return false;
}

// Whether the gate may be narrowed (GateOptions::narrow).
bool NarrowsGate(const PoseGraphOptimizerOptions& o) {
  return o.gate.estimate_noise_scale && o.gate.narrow && DecidesAtGate(o);
}

// The normalised innovation squared of each closure in `tested` against the
// map `graph` holds, solved by `map` (the odometry and the accepted
// closures, a pose held constant): r^T (I + J Sigma J^T)^-1 r, for the
// closure's whitened residual r, its Jacobian J and the map's joint
// covariance Sigma of its two poses. Where Sigma is small it is the
// closure's chi2; it is less where the map itself is uncertain.
template <typename PoseT>
std::vector<double> InnovationChi2(const FactorGraph& map, const Values& values,
                                   const std::vector<const Constraint<PoseT>*>& tested) {
  std::vector<std::pair<Key, Key>> pairs;
  for (const auto* c : tested) pairs.emplace_back(PoseKey(c->from), PoseKey(c->to));
  const std::vector<Eigen::MatrixXd> covariances = JointMarginalCovariances(map, values, pairs);
  std::vector<double> nis;
  for (std::size_t i = 0; i < tested.size(); ++i) {
    const BetweenFactor<PoseT> factor(tested[i]->from, tested[i]->to, tested[i]->measurement);
    const LinearizedFactor linear = Linearize(factor, values);
    Eigen::MatrixXd j(linear.residual.size(), covariances[i].rows());
    j << linear.jacobians[0], linear.jacobians[1];
    const Eigen::MatrixXd s =
        Eigen::MatrixXd::Identity(j.rows(), j.rows()) + j * covariances[i] * j.transpose();
    nis.push_back(linear.residual.dot(s.ldlt().solve(linear.residual)));
  }
  return nis;
}

// The ids of the closures `decisions` rejected.
std::set<ClosureId> RejectedIds(const std::vector<ClosureDecision>& decisions) {
  std::set<ClosureId> rejected;
  for (const ClosureDecision& d : decisions) {
    if (!d.accepted) rejected.insert(d.id);
  }
  return rejected;
}

// The loss of a method. Unset parameters (0) are set from the chi2 gate g so
// that a closure's weight drops below 0.5 exactly when its chi2 exceeds g, as
// for a switch: DCS's scale 2 Phi / (Phi + chi2) < 1/2 iff chi2 > 3 Phi;
// Cauchy's sqrt(1 / (1 + chi2 / b^2)) < 1/2 iff chi2 > 3 b^2; Huber's
// (b^2 / chi2)^(1/4) < 1/2 iff chi2 > 16 b^2.
RobustLoss LossFor(const PoseGraphOptimizerOptions& o, double gate) {
  auto or_gate = [](double given, double from_gate) { return given > 0.0 ? given : from_gate; };
  switch (o.method) {
    case RobustMethod::kDcs: return {RobustLoss::Type::kDcs, or_gate(o.dcs_phi, gate / 3.0)};
    case RobustMethod::kCauchy:
      return {RobustLoss::Type::kCauchy, or_gate(o.loss_scale_sigma, std::sqrt(gate / 3.0))};
    case RobustMethod::kHuber:
      return {RobustLoss::Type::kHuber, or_gate(o.loss_scale_sigma, std::sqrt(gate / 16.0))};
    default: return {};
  }
}

// rho'(chi2): the IRLS weight on the edge's chi2. Its square root scales the
// residual, as a switch does.
double LossDerivative(const RobustLoss& loss, double chi2) {
  switch (loss.type) {
    case RobustLoss::Type::kNone: return 1.0;
    case RobustLoss::Type::kScaled: return loss.scale;
    case RobustLoss::Type::kDcs: return DcsLoss::SquaredWeight(loss.scale, chi2);
    case RobustLoss::Type::kHuber: {
      const double b = loss.scale * loss.scale;
      return chi2 <= b ? 1.0 : std::sqrt(b / chi2);
    }
    case RobustLoss::Type::kCauchy: {
      const double b = loss.scale * loss.scale;
      return 1.0 / (1.0 + chi2 / b);
    }
  }
  return 1.0;
}

constexpr NameTable<InitialGuess, 4> kInitialGuessNames = {{
    {InitialGuess::kFile, "file"},
    {InitialGuess::kSpanningTree, "spanning-tree"},
    {InitialGuess::kChordal, "chordal"},
    {InitialGuess::kAuto, "auto"},
}};

// Truncated least squares by graduated non-convexity (Yang, Antonante,
// Tzoumas, Carlone, RA-L 2020, Algorithm 1 with the TLS surrogate). With the
// threshold cbar^2 (the gate) and the residuals r^2 (chi2, or the chordal
// cost) of the robust closures: start from all weights 1, mu0 = cbar^2 /
// (2 max r^2 - cbar^2); each round solves the weighted problem from the last poses, then
//   w = 1                               r^2 <= mu/(mu+1) cbar^2
//   w = 0                               r^2 >= (mu+1)/mu cbar^2
//   w = cbar/r sqrt(mu (mu+1)) - mu     otherwise
// and grows mu by `gnc_mu_step`, until the weights are binary (sum w(1-w) <
// 1e-6) or unchanged, or `gnc_max_rounds` solves, each after the first
// limited to `gnc_round_iterations`. Returns the summary of all rounds.
template <typename PoseT, typename Solve>
Summary SolveGnc(PoseGraph<PoseT>& graph, const PoseGraphOptimizerOptions& options, double cbar2,
                 std::map<ClosureId, double>& weights, Solve& solve) {
  std::map<ClosureId, const Constraint<PoseT>*> closures;
  for (const auto& c : graph.constraints) {
    if (weights.contains(c.id)) closures[c.id] = &c;
  }
  Summary total;
  double mu = 0.0;
  int round = 0;
  for (; round < options.gnc_max_rounds; ++round) {
    // The first round is the plain least-squares solve; later rounds start
    // from the previous poses and need few iterations.
    const Summary s = solve(&weights, round == 0 ? options.solver.max_iterations
                                                 : options.gnc_round_iterations);
    if (round == 0) {
      total = s;
    } else {
      total.iterations += s.iterations;
      total.AddTimes(s);
      total.final_cost = s.final_cost;
      total.termination = s.termination;
      total.message = s.message;
    }
    if (!s.IsUsable()) break;
    double max_r2 = 0.0;
    std::map<ClosureId, double> r2;
    for (const auto& [id, c] : closures) {
      max_r2 = std::max(max_r2, r2[id] = EdgeCost(graph, *c, options.cost));
    }
    if (round == 0) {
      if (max_r2 <= cbar2) break;  // every closure is an inlier: least squares is the answer
      mu = cbar2 / (2.0 * max_r2 - cbar2);
    }
    double change = 0.0, undecided = 0.0;
    for (auto& [id, w] : weights) {
      const double r = r2.at(id);
      double next = 0.0;
      if (r <= mu / (mu + 1.0) * cbar2) {
        next = 1.0;
      } else if (r < (mu + 1.0) / mu * cbar2) {
        next = std::sqrt(cbar2 / r) * std::sqrt(mu * (mu + 1.0)) - mu;
      }
      change = std::max(change, std::abs(next - w));
      undecided += next * (1.0 - next);
      w = next;
    }
    mu *= options.gnc_mu_step;
    if (undecided < 1e-6 && change < 1e-9) break;
  }
  total.message = "GNC: " + std::to_string(round + 1) + " weighted solves; last: " + total.message;
  return total;
}

// Sets the graph's poses as `guess` says; returns the guess used (kAuto's
// choice). `truncation` is the cost (in the objective `cost`) at which
// kAuto's cost of a robust constraint stops growing.
template <typename PoseT, typename IsRobust>
InitialGuess Initialize(PoseGraph<PoseT>& graph, InitialGuess guess, RelativePoseCostType cost,
                        double truncation, IsRobust robust) {
  switch (guess) {
    case InitialGuess::kFile: InitializeBySpanningTree(graph); break;
    case InitialGuess::kSpanningTree: InitializeBySpanningTree(graph, /*overwrite=*/true); break;
    case InitialGuess::kChordal: InitializeChordal(graph); break;
    case InitialGuess::kAuto: {
      InitializeBySpanningTree(graph);
      PoseGraph<PoseT> chordal = graph;
      try {
        InitializeChordal(chordal);
      } catch (const std::invalid_argument&) {
        return InitialGuess::kFile;  // disconnected: only the file's poses exist
      }
      auto robust_cost = [&](const PoseGraph<PoseT>& g) {
        double sum = 0.0;
        for (const auto& c : g.constraints) {
          const double edge = EdgeCost(g, c, cost);
          sum += robust(c) ? std::min(edge, truncation) : edge;
        }
        return sum;
      };
      if (robust_cost(chordal) >= robust_cost(graph)) return InitialGuess::kFile;
      graph.vertices = std::move(chordal.vertices);
      return InitialGuess::kChordal;
    }
  }
  return guess;
}

}  // namespace

template <typename PoseT>
RobustSolve<PoseT>::RobustSolve(PoseGraph<PoseT> graph, const PoseGraphOptimizerOptions& options)
    : graph_(std::move(graph)), options_(options), stage_start_(std::chrono::steady_clock::now()) {
  Validate(options_);
  gate_ = Gate<PoseT>(options_.cost, options_.gate.probability);
  loss_ = LossFor(options_, gate_);
}

template <typename PoseT>
PoseGraphOptimization RobustSolve<PoseT>::Run() {
  ScaleGate();
  Initialise();
  SolveRobustly();
  Narrow();
  Refine();
  Readmit();
  return Finish();
}

template <typename PoseT>
double RobustSolve<PoseT>::EndStage(const char* stage, int iterations) {
  const auto now = std::chrono::steady_clock::now();
  out_.stages.push_back({stage, std::chrono::duration<double>(now - stage_start_).count(), iterations});
  stage_start_ = now;
  return out_.stages.back().time_s;
}

template <typename PoseT>
bool RobustSolve<PoseT>::IsRobust(const Constraint<PoseT>& c) const {
  return options_.robust_odometry || c.kind != ClosureKind::kOdometry;
}

template <typename PoseT>
double RobustSolve<PoseT>::Psi(double s) const {
  return catgraph::Psi(s, options_.switch_function);
}

template <typename PoseT>
void RobustSolve<PoseT>::ScaleGate() {
  if (!options_.gate.estimate_noise_scale || options_.method == RobustMethod::kNone) return;
  out_.noise_scale = EstimateNoiseScale(graph_, options_.gate.noise_scale);
  if (out_.noise_scale.scale >= options_.gate.noise_scale_threshold) out_.gate_factor = out_.noise_scale.scale;
  gate_ = out_.gate_factor * Gate<PoseT>(options_.cost, options_.gate.probability);
  loss_ = LossFor(options_, gate_);
  EndStage("noise_scale", 0);
}

template <typename PoseT>
void RobustSolve<PoseT>::Initialise() {
  const bool any_robust = options_.method != RobustMethod::kNone ||
                          std::any_of(graph_.constraints.begin(), graph_.constraints.end(),
                                      [](const auto& c) { return c.switch_id.has_value(); });
  out_.initial_guess = Initialize(
      graph_, options_.initial_guess, options_.cost, any_robust ? gate_ : std::numeric_limits<double>::infinity(),
      [&](const Constraint<PoseT>& c) { return IsRobust(c) || c.switch_id.has_value(); });
  out_.initial_guess_time_s = EndStage("initial_guess", 0);
  initial_poses_ = graph_.vertices;

  method_decides_any_ = std::any_of(graph_.constraints.begin(), graph_.constraints.end(),
                                    [&](const auto& c) { return IsRobust(c) && !c.switch_id; });
  if (options_.method == RobustMethod::kSwitchable) {
    const double information = options_.switch_prior_information > 0.0 ? options_.switch_prior_information : gate_;
    const auto file_switches = graph_.switches;
    graph_.AddSwitches([this](const Constraint<PoseT>& c) { return IsRobust(c); }, SwitchPrior{1.0, information});
    for (const auto& [id, s] : graph_.switches) {
      if (!file_switches.contains(id)) added_switches_.insert(id);
    }
  }
  held_off_ = options_.disabled_closures;
  std::size_t disabled_found = 0;
  for (const auto& c : graph_.constraints) {
    const bool disabled = options_.disabled_closures.contains(c.id);
    disabled_found += disabled ? 1 : 0;
    if (!c.switch_id) continue;
    switch_of_.emplace(c.id, *c.switch_id);
    if (disabled) {
      disabled_switches_.insert(*c.switch_id);
      graph_.switches.at(*c.switch_id).value = 0.0;
    }
  }
  if (disabled_found != options_.disabled_closures.size()) {
    throw std::invalid_argument("disabled_closures: " +
                                std::to_string(options_.disabled_closures.size() - disabled_found) +
                                " of them are not closures of the graph");
  }
  auto switch_of_closure = [this](ClosureId id) {
    const auto found = switch_of_.find(id);
    if (found == switch_of_.end()) {
      throw std::invalid_argument("coupled_closures: closure " + std::to_string(id.value()) +
                                  " has no switch (coupled switches need method switchable)");
    }
    return found->second;
  };
  for (const auto& [child, others] : options_.coupled_closures) {
    switch_of_closure(child);
    for (const ClosureId other : others) coupled_switches_[child].push_back(switch_of_closure(other));
  }

  robust_solve_ = options_.method != RobustMethod::kNone || !graph_.switches.empty();
  if (options_.refinement.stop_when_settled && options_.refinement.enabled && robust_solve_ &&
      options_.method != RobustMethod::kGnc) {
    // Each solve runs its own copy of the test, which starts with no history.
    settled_ = [this, last = std::vector<bool>{}, unchanged = 0](const Values& values, double decrease) mutable {
      TakeSolution(values);
      std::vector<bool> accepted;
      for (const ClosureDecision& d : DecideAll(nullptr)) accepted.push_back(d.accepted);
      unchanged = accepted == last ? unchanged + 1 : 0;
      last = std::move(accepted);
      return unchanged >= options_.refinement.settled_iterations && decrease < options_.refinement.settled_decrease;
    };
  }
}

template <typename PoseT>
void RobustSolve<PoseT>::AddPoses(FactorGraph& factors, Values& values, const Poses& poses) const {
  for (const auto& [id, v] : poses) {
    values.Insert(id, *v.pose);
    if (v.fixed) factors.SetConstant(PoseKey(id));
  }
  if (std::none_of(graph_.vertices.begin(), graph_.vertices.end(), [](const auto& v) { return v.second.fixed; })) {
    factors.SetConstant(PoseKey(graph_.vertices.begin()->first));  // gauge
  }
}

template <typename PoseT>
void RobustSolve<PoseT>::TakePoses(const Values& values) {
  for (auto& [id, v] : graph_.vertices) {
    if constexpr (std::is_same_v<PoseT, Pose2>) {
      v.pose = values.AtPose2(id);
    } else {
      v.pose = values.AtPose3(id);
    }
  }
}

template <typename PoseT>
void RobustSolve<PoseT>::TakeSolution(const Values& values) {
  TakePoses(values);
  for (auto& [id, s] : graph_.switches) {
    if (!disabled_switches_.contains(id) && !frozen_switches_.contains(id)) s.value = values.AtSwitch(id);
  }
}

template <typename PoseT>
Summary RobustSolve<PoseT>::Solve(const std::map<ClosureId, double>* gnc_weights, int max_iterations) {
  Values initial;
  FactorGraph factors;
  AddPoses(factors, initial, graph_.vertices);
  for (const auto& [id, s] : graph_.switches) {
    if (disabled_switches_.contains(id)) continue;
    initial.Insert(id, s.value);
    if (frozen_switches_.contains(id)) {
      factors.SetConstant(SwitchKey(id));  // a coupled closure may still read it
    } else if (s.prior) {
      factors.Emplace<SwitchPriorFactor>(id, *s.prior);
    }
  }
  for (const auto& c : graph_.constraints) {
    if (held_off_.contains(c.id)) continue;
    if (c.switch_id) {
      const auto coupled = coupled_switches_.find(c.id);
      factors.Emplace<SwitchableBetweenFactor<PoseT>>(
          c.from, c.to, *c.switch_id, c.measurement, options_.switch_function,
          coupled == coupled_switches_.end() ? std::vector<SwitchId>{} : coupled->second, options_.cost);
      continue;
    }
    RobustLoss edge_loss = IsRobust(c) ? loss_ : RobustLoss{};
    if (gnc_weights && IsRobust(c)) {
      const double w = gnc_weights->at(c.id);
      if (w == 0.0) continue;
      edge_loss = {RobustLoss::Type::kScaled, w};
    }
    factors.Emplace<BetweenFactor<PoseT>>(c.from, c.to, c.measurement, edge_loss, options_.cost);
  }
  OptimizerOptions solver = options_.solver;
  solver.max_iterations = std::min(solver.max_iterations, max_iterations);
  if (!gnc_weights) solver.stop_test = settled_;
  OptimizationResult solved = Optimize(factors, initial, solver);
  TakeSolution(solved.values);
  if (solved.summary.stopped_by_test) {
    std::ostringstream message;
    message << "decisions settled: none changed over the last " << options_.refinement.settled_iterations
            << " iterations, and the last lowered the cost by less than " << options_.refinement.settled_decrease
            << " (relative); the refinement re-solves the map";
    solved.summary.message = message.str();
  }
  return solved.summary;
}

template <typename PoseT>
Summary RobustSolve<PoseT>::SolveAtGate(double g) {
  loss_ = LossFor(options_, g);
  if (options_.method != RobustMethod::kGnc) return Solve(nullptr, options_.solver.max_iterations);
  gnc_weights_.clear();
  for (const auto& c : graph_.constraints) {
    if (!c.switch_id && IsRobust(c) && !held_off_.contains(c.id)) gnc_weights_[c.id] = 1.0;
  }
  auto solve = [this](const std::map<ClosureId, double>* weights, int max_iterations) {
    return Solve(weights, max_iterations);
  };
  return SolveGnc(graph_, options_, g, gnc_weights_, solve);
}

template <typename PoseT>
ClosureDecision RobustSolve<PoseT>::Decide(const Constraint<PoseT>& c) const {
  ClosureDecision d{c.id, c.from, c.to, c.kind, 1.0, 1.0, true};
  bool coupled_on = true;  // every coupled switch above 0.5
  double own = 1.0;        // the closure's own switch or loss weight
  if (options_.disabled_closures.contains(c.id)) {
    d.weight = own = 0.0;
  } else if (c.switch_id) {
    own = Psi(graph_.switches.at(*c.switch_id).value);
    d.weight = own;
    if (const auto coupled = coupled_switches_.find(c.id); coupled != coupled_switches_.end()) {
      for (const SwitchId other : coupled->second) {
        const double w = Psi(graph_.switches.at(other).value);
        coupled_on = coupled_on && w > 0.5;
        d.weight *= w;
      }
    }
  } else if (options_.method == RobustMethod::kGnc && IsRobust(c)) {
    d.weight = gnc_weights_.at(c.id);
  } else if (IsRobust(c)) {
    d.weight = std::sqrt(LossDerivative(loss_, EdgeCost(graph_, c, options_.cost)));
  }
  if (!c.switch_id) own = d.weight;
  d.own_weight = own;
  d.accepted = own > 0.5 && coupled_on;
  return d;
}

template <typename PoseT>
std::vector<ClosureDecision> RobustSolve<PoseT>::DecideAll(const std::vector<ClosureDecision>* kept) const {
  std::vector<ClosureDecision> decisions;
  for (const auto& c : graph_.constraints) {
    if (c.kind == ClosureKind::kOdometry && !c.switch_id) continue;
    if (kept && !(*kept)[decisions.size()].accepted) {
      decisions.push_back((*kept)[decisions.size()]);
      continue;
    }
    decisions.push_back(Decide(c));
  }
  return decisions;
}

template <typename PoseT>
void RobustSolve<PoseT>::SolveRobustly() {
  out_.summary = SolveAtGate(gate_);
  out_.closures = DecideAll(nullptr);
  EndStage("robust_solve", out_.summary.iterations);
}

template <typename PoseT>
void RobustSolve<PoseT>::Narrow() {
  // The accepted closures' own cycles measure the noise again; when it is
  // Gaussian and the information overstates it, they are decided again at
  // the calibrated family-wise gate, from the first solve's poses, the
  // rejected ones held off as they are (GateOptions::narrow).
  if (!NarrowsGate(options_) || !method_decides_any_ || !out_.summary.IsUsable()) return;
  const GateOptions& o = options_.gate;
  const std::set<ClosureId> rejected = RejectedIds(out_.closures);
  const std::size_t tested = out_.closures.size() - rejected.size();
  out_.inlier_noise_scale = EstimateNoiseScale(graph_, o.noise_scale, rejected);
  const NoiseScaleEstimate& inliers = out_.inlier_noise_scale;
  const double narrowed =
      tested == 0 ? gate_
                  : inliers.upper_scale *
                        Gate<PoseT>(options_.cost, 1.0 - (1.0 - o.probability) / static_cast<double>(tested));
  if (inliers.cycles >= o.narrow_min_cycles && inliers.upper_scale <= o.narrow_max_tail_ratio * inliers.scale &&
      narrowed * o.noise_scale_threshold <= gate_) {
    const auto first_vertices = graph_.vertices;
    const auto first_switches = graph_.switches;
    for (const ClosureId id : rejected) {
      held_off_.insert(id);
      if (const auto s = switch_of_.find(id); s != switch_of_.end()) frozen_switches_.insert(s->second);
    }
    for (const SwitchId id : added_switches_) {
      if (frozen_switches_.contains(id) || disabled_switches_.contains(id)) continue;
      SwitchVariable& s = graph_.switches.at(id);
      s.value = 1.0;
      s.prior->information = narrowed;
    }
    out_.narrowed = SolveAtGate(narrowed);
    std::vector<ClosureDecision> second;
    if (out_.narrowed->IsUsable()) {
      second = DecideAll(&out_.closures);
      for (const ClosureDecision& d : second) out_.narrow_newly_rejected += d.accepted ? 0 : 1;
      out_.narrow_newly_rejected -= rejected.size();
    }
    if (out_.narrowed->IsUsable() &&
        static_cast<double>(out_.narrow_newly_rejected) <= o.narrow_max_rejected_share * static_cast<double>(tested)) {
      out_.narrow_factor = narrowed / gate_;
      out_.closures = std::move(second);
    } else {
      graph_.vertices = first_vertices;  // the first solve's result stands
      graph_.switches = first_switches;
    }
  }
  EndStage("narrow", out_.narrowed ? out_.narrowed->iterations : 0);
}

template <typename PoseT>
void RobustSolve<PoseT>::AddMap(FactorGraph& factors, Values& values, const Poses& poses) const {
  AddPoses(factors, values, poses);
  const std::set<ClosureId> rejected = RejectedIds(out_.closures);
  for (const auto& c : graph_.constraints) {
    if (rejected.contains(c.id)) continue;
    factors.Emplace<BetweenFactor<PoseT>>(c.from, c.to, c.measurement, RobustLoss{}, options_.cost);
  }
}

template <typename PoseT>
Summary RobustSolve<PoseT>::RefineFrom(bool from_initial_guess) {
  std::optional<OptimizationResult> best;
  Summary times;  // of every start
  std::optional<Summary> failed;
  std::vector<const Poses*> starts = {&graph_.vertices};
  if (from_initial_guess) starts.push_back(&initial_poses_);
  for (const Poses* start_poses : starts) {
    Values start;
    FactorGraph factors;
    AddMap(factors, start, *start_poses);
    OptimizationResult refined = Optimize(factors, start, options_.solver);
    times.AddTimes(refined.summary);
    if (refined.summary.IsUsable() && (!best || refined.summary.final_cost < best->summary.final_cost)) {
      best = std::move(refined);
    } else if (!best && !failed) {
      failed = refined.summary;  // reported if no start succeeds
    }
  }
  Summary summary = best ? best->summary : *failed;
  if (best) TakePoses(best->values);
  summary.SetTimes(times);
  return summary;
}

template <typename PoseT>
void RobustSolve<PoseT>::Refine() {
  // The decisions stand; the poses are re-solved by plain least squares over
  // the odometry and the accepted closures at full weight, so that the
  // residual pull of rejected closures (weight up to 0.5) and the
  // down-weighting of accepted ones leave no bias in the map. It starts
  // from the robust solution and, when the robust solve rejected any
  // closure, from the initial guess too, and keeps the lower cost: a method
  // that decides right on a map its early rounds folded (GNC after a
  // least-squares start among outliers) ends in a poor local minimum, which
  // the initial guess avoids. With nothing rejected, the robust solve ran
  // from the initial guess with every closure near full weight, the
  // refinement's own problem: a second start ends where the first does.
  if (!options_.refinement.enabled || !robust_solve_ || !out_.summary.IsUsable()) return;
  out_.refinement = RefineFrom(/*from_initial_guess=*/!RejectedIds(out_.closures).empty());
  EndStage("refine", out_.refinement->iterations);
}

template <typename PoseT>
void RobustSolve<PoseT>::Readmit() {
  // Each closure the method rejected is tested once more against the
  // refined map, by its innovation (the map's own uncertainty counted) at
  // the family-wise gate; those that pass are accepted and the map refined
  // again, and the rest tested against that map, until none passes (at
  // most kRounds) (ReadmissionOptions).
  if (!options_.readmission.enabled || !DecidesAtGate(options_) || options_.cost != RelativePoseCostType::kG2o ||
      out_.narrowed || !out_.refinement || !out_.refinement->IsUsable()) {
    return;
  }
  constexpr int kRounds = 3;
  std::map<ClosureId, const Constraint<PoseT>*> constraint_of;
  for (const auto& c : graph_.constraints) constraint_of.emplace(c.id, &c);
  auto by_method = [&](const ClosureDecision& d) {
    const Constraint<PoseT>& c = *constraint_of.at(d.id);
    return IsRobust(c) && (!c.switch_id || added_switches_.contains(*c.switch_id)) &&
           !options_.disabled_closures.contains(d.id);
  };
  // The family-wise gate for the n closures the method decided.
  const auto decided = std::count_if(out_.closures.begin(), out_.closures.end(), by_method);
  const double family_gate =
      decided == 0 ? 0.0
                   : out_.gate_factor * Gate<PoseT>(options_.cost, 1.0 - (1.0 - options_.gate.probability) /
                                                                          static_cast<double>(decided));
  // Rejected by its own weight, with every coupled switch on.
  auto rejected_by_itself = [&](const ClosureDecision& d) {
    if (d.accepted || d.own_weight > 0.5) return false;
    const auto coupled = coupled_switches_.find(d.id);
    return coupled == coupled_switches_.end() ||
           std::all_of(coupled->second.begin(), coupled->second.end(),
                       [&](SwitchId s) { return Psi(graph_.switches.at(s).value) > 0.5; });
  };
  Summary times;  // of the refinements
  int iterations = 0;
  for (int round = 0; round < kRounds; ++round) {
    std::vector<ClosureDecision*> candidates;
    std::vector<const Constraint<PoseT>*> tested;
    for (ClosureDecision& d : out_.closures) {
      if (!rejected_by_itself(d) || !by_method(d)) continue;
      candidates.push_back(&d);
      tested.push_back(constraint_of.at(d.id));
    }
    if (candidates.empty()) break;
    const auto start = std::chrono::steady_clock::now();
    Values values;
    FactorGraph map;
    AddMap(map, values, graph_.vertices);
    std::vector<double> nis;
    try {
      nis = InnovationChi2<PoseT>(map, values, tested);
    } catch (const std::runtime_error&) {
      // The accepted closures leave the map undetermined: nothing to test against.
    }
    out_.readmit_test_time_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::vector<ClosureDecision*> passed;
    for (std::size_t i = 0; i < nis.size(); ++i) {
      if (nis[i] <= family_gate) passed.push_back(candidates[i]);
    }
    if (passed.empty()) break;
    const auto decisions_before = out_.closures;
    const auto switches_before = graph_.switches;
    const auto vertices_before = graph_.vertices;
    for (ClosureDecision* d : passed) {
      d->accepted = d->readmitted = true;
      d->weight = d->own_weight = 1.0;
      if (const auto s = switch_of_.find(d->id); s != switch_of_.end()) graph_.switches.at(s->second).value = 1.0;
    }
    Summary refined = RefineFrom(false);
    times.AddTimes(refined);
    iterations += refined.iterations;
    if (!refined.IsUsable()) {  // the last map and its decisions stand
      out_.closures = decisions_before;
      graph_.switches = switches_before;
      graph_.vertices = vertices_before;
      break;
    }
    out_.readmitted += passed.size();
    out_.readmission = refined;
  }
  if (out_.readmission) out_.readmission->SetTimes(times);
  EndStage("readmit", iterations);
}

template <typename PoseT>
PoseGraphOptimization RobustSolve<PoseT>::Finish() {
  for (const ClosureDecision& d : out_.closures) (d.accepted ? out_.accepted : out_.rejected) += 1;
  // The decisions travel with the graph, so that a reader of the written
  // file counts a closure as this solve did.
  if (options_.method != RobustMethod::kNone) {
    std::map<ClosureId, RobustDecision> decided;
    for (const ClosureDecision& d : out_.closures) decided.emplace(d.id, RobustDecision{d.accepted, d.weight});
    for (auto& c : graph_.constraints) {
      const auto it = decided.find(c.id);
      c.decision = it == decided.end() ? std::nullopt : std::optional<RobustDecision>(it->second);
    }
  }
  out_.chi2 = GraphChi2(graph_);
  out_.chordal_cost = GraphChordalCost(graph_);
  out_.graph = std::move(graph_);
  EndStage("costs", 0);
  return std::move(out_);
}

template class RobustSolve<Pose2>;
template class RobustSolve<Pose3>;

namespace {

template <typename PoseT>
PoseGraph<PoseT> Drop(PoseGraph<PoseT> graph, const std::vector<ClosureDecision>& decisions) {
  const std::set<ClosureId> rejected = RejectedIds(decisions);
  std::erase_if(graph.constraints, [&](const Constraint<PoseT>& c) {
    return rejected.contains(c.id) || !graph.IsAccepted(c);
  });
  for (auto& c : graph.constraints) c.switch_id.reset(), c.decision.reset();
  graph.switches.clear();
  return graph;
}

}  // namespace

std::string_view ToString(RobustMethod method) { return NameOf(kMethodNames, method); }

std::optional<RobustMethod> RobustMethodFromString(std::string_view text) {
  return ValueOf(kMethodNames, text);
}

std::vector<std::string> RobustMethodNames() { return NamesOf(kMethodNames); }

std::string_view ToString(InitialGuess guess) { return NameOf(kInitialGuessNames, guess); }

std::optional<InitialGuess> InitialGuessFromString(std::string_view text) {
  return ValueOf(kInitialGuessNames, text);
}

void Validate(const PoseGraphOptimizerOptions& o) {
  if (!(o.switch_prior_information >= 0.0)) {
    throw std::invalid_argument("switch_prior_information must be >= 0 (0: use the gate)");
  }
  if (!(o.gnc_mu_step > 1.0)) {
    throw std::invalid_argument("gnc_mu_step must be > 1, got " + std::to_string(o.gnc_mu_step));
  }
  if (o.gnc_round_iterations < 1) {
    throw std::invalid_argument("gnc_round_iterations must be >= 1, got " +
                                std::to_string(o.gnc_round_iterations));
  }
  if (o.gnc_max_rounds < 1) {
    throw std::invalid_argument("gnc_max_rounds must be >= 1, got " +
                                std::to_string(o.gnc_max_rounds));
  }
  if (!(o.gate.probability > 0.0 && o.gate.probability < 1.0)) {
    throw std::invalid_argument("gate.probability must be in (0, 1)");
  }
  if (!(o.gate.noise_scale_threshold > 1.0)) throw std::invalid_argument("gate.noise_scale_threshold must be > 1");
  if (!(o.gate.narrow_max_tail_ratio >= 1.0)) throw std::invalid_argument("gate.narrow_max_tail_ratio must be >= 1");
  if (o.gate.narrow_min_cycles < 1) throw std::invalid_argument("gate.narrow_min_cycles must be >= 1");
  if (!(o.gate.narrow_max_rejected_share > 0.0 && o.gate.narrow_max_rejected_share <= 1.0)) {
    throw std::invalid_argument("gate.narrow_max_rejected_share must be in (0, 1]");
  }
  Validate(o.gate.noise_scale);
  if (o.refinement.settled_iterations < 1) throw std::invalid_argument("refinement.settled_iterations must be >= 1");
  if (!(o.refinement.settled_decrease > 0.0)) throw std::invalid_argument("refinement.settled_decrease must be > 0");
  if (!(o.dcs_phi >= 0.0)) throw std::invalid_argument("dcs_phi must be >= 0 (0: from the gate)");
  if (!(o.loss_scale_sigma >= 0.0)) {
    throw std::invalid_argument("loss_scale_sigma must be >= 0 (0: from the gate)");
  }
  Validate(o.solver);
}

PoseGraphOptimization OptimizePoseGraph(const AnyPoseGraph& graph,
                                        const PoseGraphOptimizerOptions& options) {
  return std::visit(
      [&](const auto& g) {
        using PoseT = typename std::decay_t<decltype(g)>::Pose;
        return RobustSolve<PoseT>(g, options).Run();
      },
      graph);
}

double PoseGraphOptimization::WallTimeS() const {
  double total = 0.0;
  for (const StageTime& s : stages) total += s.time_s;
  return total;
}

double ChordalCost(const AnyPoseGraph& graph) {
  return std::visit([](const auto& g) { return GraphChordalCost(g); }, graph);
}

double Chi2(const AnyPoseGraph& graph) {
  return std::visit([](const auto& g) { return GraphChi2(g); }, graph);
}

AnyPoseGraph DropRejected(const AnyPoseGraph& graph,
                          const std::vector<ClosureDecision>& decisions) {
  return std::visit([&](const auto& g) { return AnyPoseGraph(Drop(g, decisions)); }, graph);
}

}  // namespace catgraph
