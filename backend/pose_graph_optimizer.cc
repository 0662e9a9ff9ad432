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

template <typename PoseT>
PoseGraphOptimization Run(PoseGraph<PoseT> graph, const PoseGraphOptimizerOptions& options) {
  PoseGraphOptimization out;
  // Ends a stage: its time is the wall clock since the last stage ended.
  auto stage_start = std::chrono::steady_clock::now();
  auto end_stage = [&](const char* stage, int iterations) {
    const auto now = std::chrono::steady_clock::now();
    out.stages.push_back({stage, std::chrono::duration<double>(now - stage_start).count(), iterations});
    stage_start = now;
    return out.stages.back().time_s;
  };
  const bool switchable = options.method == RobustMethod::kSwitchable;
  NoiseScaleEstimate noise_scale;
  double gate_factor = 1.0;
  if (options.gate.estimate_noise_scale && options.method != RobustMethod::kNone) {
    noise_scale = EstimateNoiseScale(graph, options.gate.noise_scale);
    if (noise_scale.scale >= options.gate.noise_scale_threshold) gate_factor = noise_scale.scale;
    end_stage("noise_scale", 0);
  }
  const double gate = gate_factor * Gate<PoseT>(options.cost, options.gate.probability);
  RobustLoss loss = LossFor(options, gate);
  auto robust = [&](const Constraint<PoseT>& c) {
    return options.robust_odometry || c.kind != ClosureKind::kOdometry;
  };
  const bool any_robust = options.method != RobustMethod::kNone ||
                          std::any_of(graph.constraints.begin(), graph.constraints.end(),
                                      [](const auto& c) { return c.switch_id.has_value(); });
  const InitialGuess initial_guess = Initialize(
      graph, options.initial_guess, options.cost, any_robust ? gate : std::numeric_limits<double>::infinity(),
      [&](const Constraint<PoseT>& c) { return robust(c) || c.switch_id.has_value(); });
  const double initial_guess_time_s = end_stage("initial_guess", 0);
  const std::map<PoseId, Vertex<PoseT>> initial_poses = graph.vertices;

  // Closures the method decides (the rest carry the file's switches).
  const bool method_decides_any = std::any_of(graph.constraints.begin(), graph.constraints.end(),
                                              [&](const auto& c) { return robust(c) && !c.switch_id; });
  std::set<SwitchId> added_switches;  // the method's, as opposed to the file's
  if (switchable) {
    const double switch_information =
        options.switch_prior_information > 0.0 ? options.switch_prior_information : gate;
    const auto file_switches = graph.switches;
    graph.AddSwitches(robust, SwitchPrior{1.0, switch_information});
    for (const auto& [id, s] : graph.switches) {
      if (!file_switches.contains(id)) added_switches.insert(id);
    }
  }

  // Closure -> switch, for the coupled switches; the disabled closures'
  // switches. Closures held off are left out of a solve: the disabled ones,
  // and in the narrowed solve the ones the first rejected, whose switches
  // are then held at their values (`frozen_switches`).
  std::map<ClosureId, SwitchId> switch_of;
  std::set<SwitchId> disabled_switches, frozen_switches;
  std::set<ClosureId> held_off = options.disabled_closures;
  std::size_t disabled_found = 0;
  for (const auto& c : graph.constraints) {
    const bool disabled = options.disabled_closures.contains(c.id);
    disabled_found += disabled ? 1 : 0;
    if (!c.switch_id) continue;
    switch_of.emplace(c.id, *c.switch_id);
    if (disabled) {
      disabled_switches.insert(*c.switch_id);
      graph.switches.at(*c.switch_id).value = 0.0;
    }
  }
  if (disabled_found != options.disabled_closures.size()) {
    throw std::invalid_argument("disabled_closures: " +
                                std::to_string(options.disabled_closures.size() - disabled_found) +
                                " of them are not closures of the graph");
  }
  std::map<ClosureId, std::vector<SwitchId>> coupled_switches;
  auto switch_of_closure = [&switch_of](ClosureId id) {
    const auto found = switch_of.find(id);
    if (found == switch_of.end()) {
      throw std::invalid_argument("coupled_closures: closure " + std::to_string(id.value()) +
                                  " has no switch (coupled switches need method switchable)");
    }
    return found->second;
  };
  for (const auto& [child, others] : options.coupled_closures) {
    switch_of_closure(child);
    for (const ClosureId other : others) coupled_switches[child].push_back(switch_of_closure(other));
  }
  auto psi = [&options](double s) { return Psi(s, options.switch_function); };

  // The poses and the gauge, shared by the robust solve and the refinement.
  auto add_poses = [&graph](FactorGraph& factors, Values& values,
                            const std::map<PoseId, Vertex<PoseT>>& poses) {
    for (const auto& [id, v] : poses) {
      values.Insert(id, *v.pose);
      if (v.fixed) factors.SetConstant(PoseKey(id));
    }
    if (std::none_of(graph.vertices.begin(), graph.vertices.end(),
                     [](const auto& v) { return v.second.fixed; })) {
      factors.SetConstant(PoseKey(graph.vertices.begin()->first));  // gauge
    }
  };
  auto take_poses = [&graph](const Values& values) {
    for (auto& [id, v] : graph.vertices) {
      if constexpr (std::is_same_v<PoseT, Pose2>) {
        v.pose = values.AtPose2(id);
      } else {
        v.pose = values.AtPose3(id);
      }
    }
  };

  auto take_solution = [&](const Values& values) {
    take_poses(values);
    for (auto& [id, s] : graph.switches) {
      if (!disabled_switches.contains(id) && !frozen_switches.contains(id)) s.value = values.AtSwitch(id);
    }
  };
  // The robust solve's stop test (RefinementOptions::stop_when_settled),
  // set below where the decisions are defined.
  std::function<bool(const Values&, double)> settled;

  // One solve of the whole graph; `gnc_weights`, when given, scales each
  // robust closure's chi2 (a zero weight leaves the closure out).
  auto solve = [&](const std::map<ClosureId, double>* gnc_weights, int max_iterations) {
    Values initial;
    FactorGraph factors;
    add_poses(factors, initial, graph.vertices);
    for (const auto& [id, s] : graph.switches) {
      if (disabled_switches.contains(id)) continue;
      initial.Insert(id, s.value);
      if (frozen_switches.contains(id)) {
        factors.SetConstant(SwitchKey(id));  // a coupled closure may still read it
      } else if (s.prior) {
        factors.Emplace<SwitchPriorFactor>(id, *s.prior);
      }
    }
    for (const auto& c : graph.constraints) {
      if (held_off.contains(c.id)) continue;
      if (c.switch_id) {
        const auto coupled = coupled_switches.find(c.id);
        factors.Emplace<SwitchableBetweenFactor<PoseT>>(
            c.from, c.to, *c.switch_id, c.measurement, options.switch_function,
            coupled == coupled_switches.end() ? std::vector<SwitchId>{} : coupled->second, options.cost);
        continue;
      }
      RobustLoss edge_loss = robust(c) ? loss : RobustLoss{};
      if (gnc_weights && robust(c)) {
        const double w = gnc_weights->at(c.id);
        if (w == 0.0) continue;
        edge_loss = {RobustLoss::Type::kScaled, w};
      }
      factors.Emplace<BetweenFactor<PoseT>>(c.from, c.to, c.measurement, edge_loss, options.cost);
    }
    OptimizerOptions solver = options.solver;
    solver.max_iterations = std::min(solver.max_iterations, max_iterations);
    if (!gnc_weights) solver.stop_test = settled;
    OptimizationResult solved = Optimize(factors, initial, solver);
    take_solution(solved.values);
    if (solved.summary.stopped_by_test) {
      std::ostringstream message;
      message << "decisions settled: none changed over the last " << options.refinement.settled_iterations
              << " iterations, and the last lowered the cost by less than " << options.refinement.settled_decrease
              << " (relative); the refinement re-solves the map";
      solved.summary.message = message.str();
    }
    return solved.summary;
  };

  // The robust solve at the gate g, over the closures not held off.
  std::map<ClosureId, double> gnc_weights;
  auto solve_robustly = [&](double g) {
    loss = LossFor(options, g);
    if (options.method != RobustMethod::kGnc) return solve(nullptr, options.solver.max_iterations);
    gnc_weights.clear();
    for (const auto& c : graph.constraints) {
      if (!c.switch_id && robust(c) && !held_off.contains(c.id)) gnc_weights[c.id] = 1.0;
    }
    return SolveGnc(graph, options, g, gnc_weights, solve);
  };

  // What the last solve decided about loop closure c.
  auto decide_one = [&](const Constraint<PoseT>& c) {
    ClosureDecision d{c.id, c.from, c.to, c.kind, 1.0, 1.0, true};
    bool coupled_on = true;  // every coupled switch above 0.5
    double own = 1.0;        // the closure's own switch or loss weight
    if (options.disabled_closures.contains(c.id)) {
      d.weight = own = 0.0;
    } else if (c.switch_id) {
      own = psi(graph.switches.at(*c.switch_id).value);
      d.weight = own;
      if (const auto coupled = coupled_switches.find(c.id); coupled != coupled_switches.end()) {
        for (const SwitchId other : coupled->second) {
          const double w = psi(graph.switches.at(other).value);
          coupled_on = coupled_on && w > 0.5;
          d.weight *= w;
        }
      }
    } else if (options.method == RobustMethod::kGnc && robust(c)) {
      d.weight = gnc_weights.at(c.id);
    } else if (robust(c)) {
      d.weight = std::sqrt(LossDerivative(loss, EdgeCost(graph, c, options.cost)));
    }
    if (!c.switch_id) own = d.weight;
    d.own_weight = own;
    d.accepted = own > 0.5 && coupled_on;
    return d;
  };
  // ... about every loop closure, in graph order; where `kept` (the first
  // solve's decisions) rejected one, that decision.
  auto decide_all = [&](const std::vector<ClosureDecision>* kept) {
    std::vector<ClosureDecision> decisions;
    for (const auto& c : graph.constraints) {
      if (c.kind == ClosureKind::kOdometry && !c.switch_id) continue;
      if (kept && !(*kept)[decisions.size()].accepted) {
        decisions.push_back((*kept)[decisions.size()]);
        continue;
      }
      decisions.push_back(decide_one(c));
    }
    return decisions;
  };

  // Each solve runs its own copy of the test, which starts with no history.
  const bool robust_solve = options.method != RobustMethod::kNone || !graph.switches.empty();
  if (options.refinement.stop_when_settled && options.refinement.enabled && robust_solve && options.method != RobustMethod::kGnc) {
    settled = [&, last = std::vector<bool>{}, unchanged = 0](const Values& values,
                                                            double decrease) mutable {
      take_solution(values);
      std::vector<bool> accepted;
      for (const ClosureDecision& d : decide_all(nullptr)) accepted.push_back(d.accepted);
      unchanged = accepted == last ? unchanged + 1 : 0;
      last = std::move(accepted);
      return unchanged >= options.refinement.settled_iterations && decrease < options.refinement.settled_decrease;
    };
  }

  out.summary = solve_robustly(gate);
  out.closures = decide_all(nullptr);
  end_stage("robust_solve", out.summary.iterations);

  // Narrowing (GateOptions::narrow): the accepted
  // closures' own cycles measure the noise again; when it is Gaussian and
  // the information overstates it, they are decided again at the calibrated
  // family-wise gate, from the first solve's poses, the rejected ones held
  // off as they are.
  if (NarrowsGate(options) && method_decides_any && out.summary.IsUsable()) {
    const std::set<ClosureId> rejected = RejectedIds(out.closures);
    const std::size_t tested = out.closures.size() - rejected.size();
    out.inlier_noise_scale = EstimateNoiseScale(graph, options.gate.noise_scale, rejected);
    const NoiseScaleEstimate& inliers = out.inlier_noise_scale;
    const double narrowed =
        tested == 0 ? gate
                    : inliers.upper_scale *
                          Gate<PoseT>(options.cost, 1.0 - (1.0 - options.gate.probability) /
                                                              static_cast<double>(tested));
    if (inliers.cycles >= options.gate.narrow_min_cycles &&
        inliers.upper_scale <= options.gate.narrow_max_tail_ratio * inliers.scale &&
        narrowed * options.gate.noise_scale_threshold <= gate) {
      const auto first_vertices = graph.vertices;
      const auto first_switches = graph.switches;
      for (const ClosureId id : rejected) {
        held_off.insert(id);
        if (const auto s = switch_of.find(id); s != switch_of.end()) frozen_switches.insert(s->second);
      }
      for (const SwitchId id : added_switches) {
        if (frozen_switches.contains(id) || disabled_switches.contains(id)) continue;
        SwitchVariable& s = graph.switches.at(id);
        s.value = 1.0;
        s.prior->information = narrowed;
      }
      out.narrowed = solve_robustly(narrowed);
      std::vector<ClosureDecision> second;
      if (out.narrowed->IsUsable()) {
        second = decide_all(&out.closures);
        for (const ClosureDecision& d : second) out.narrow_newly_rejected += d.accepted ? 0 : 1;
        out.narrow_newly_rejected -= rejected.size();
      }
      if (out.narrowed->IsUsable() &&
          static_cast<double>(out.narrow_newly_rejected) <=
              options.gate.narrow_max_rejected_share * static_cast<double>(tested)) {
        out.narrow_factor = narrowed / gate;
        out.closures = std::move(second);
      } else {
        graph.vertices = first_vertices;  // the first solve's result stands
        graph.switches = first_switches;
      }
    }
    end_stage("narrow", out.narrowed ? out.narrowed->iterations : 0);
  }
  out.initial_guess = initial_guess;
  out.initial_guess_time_s = initial_guess_time_s;
  out.noise_scale = noise_scale;
  out.gate_factor = gate_factor;

  // The map of the odometry and the accepted closures at full weight, as
  // factors over the graph's poses.
  auto map_factors = [&](FactorGraph& factors, Values& values, const std::map<PoseId, Vertex<PoseT>>& poses) {
    add_poses(factors, values, poses);
    const std::set<ClosureId> rejected = RejectedIds(out.closures);
    for (const auto& c : graph.constraints) {
      if (rejected.contains(c.id)) continue;
      factors.Emplace<BetweenFactor<PoseT>>(c.from, c.to, c.measurement, RobustLoss{}, options.cost);
    }
  };
  // Refinement: the decisions stand; the poses are re-solved by plain least
  // squares over the odometry and the accepted closures at full weight, so
  // that the residual pull of rejected closures (weight up to 0.5) and the
  // down-weighting of accepted ones leave no bias in the map. It starts from
  // the robust solution and, with `from_initial_guess`, from the initial
  // guess too, and keeps the lower cost: a method that decides right on a
  // map its early rounds folded (GNC after a least-squares start among
  // outliers) ends in a poor local minimum, which the initial guess avoids.
  auto refine = [&](bool from_initial_guess) {
    std::optional<OptimizationResult> best;
    Summary times;  // of every start
    std::optional<Summary> failed;
    using Poses = std::map<PoseId, Vertex<PoseT>>;
    std::vector<const Poses*> starts = {&graph.vertices};
    if (from_initial_guess) starts.push_back(&initial_poses);
    for (const Poses* start_poses : starts) {
      Values start;
      FactorGraph factors;
      map_factors(factors, start, *start_poses);
      OptimizationResult refined = Optimize(factors, start, options.solver);
      times.AddTimes(refined.summary);
      if (refined.summary.IsUsable() && (!best || refined.summary.final_cost < best->summary.final_cost)) {
        best = std::move(refined);
      } else if (!best && !failed) {
        failed = refined.summary;  // reported if no start succeeds
      }
    }
    Summary summary = best ? best->summary : *failed;
    if (best) take_poses(best->values);
    summary.SetTimes(times);
    return summary;
  };
  if (options.refinement.enabled && robust_solve && out.summary.IsUsable()) {
    // With nothing rejected, the robust solve ran from the initial guess
    // with every closure near full weight, the refinement's own problem: a
    // second start from the initial guess ends where the first does.
    out.refinement = refine(/*from_initial_guess=*/!RejectedIds(out.closures).empty());
    end_stage("refine", out.refinement->iterations);
  }

  // Readmission (ReadmissionOptions): each closure the
  // method rejected is tested once more against the refined map, by its
  // innovation (the map's own uncertainty counted) at the family-wise gate;
  // those that pass are accepted and the map refined again, and the rest
  // tested against that map, until none passes (at most kReadmitRounds).
  if (options.readmission.enabled && DecidesAtGate(options) && options.cost == RelativePoseCostType::kG2o &&
      !out.narrowed && out.refinement && out.refinement->IsUsable()) {
    constexpr int kReadmitRounds = 3;
    std::map<ClosureId, const Constraint<PoseT>*> constraint_of;
    for (const auto& c : graph.constraints) constraint_of.emplace(c.id, &c);
    auto by_method = [&](const ClosureDecision& d) {
      const Constraint<PoseT>& c = *constraint_of.at(d.id);
      return robust(c) && (!c.switch_id || added_switches.contains(*c.switch_id)) &&
             !options.disabled_closures.contains(d.id);
    };
    // The family-wise gate for the n closures the method decided.
    const auto decided = std::count_if(out.closures.begin(), out.closures.end(), by_method);
    const double family_gate =
        decided == 0 ? 0.0
                     : gate_factor * Gate<PoseT>(options.cost, 1.0 - (1.0 - options.gate.probability) /
                                                                      static_cast<double>(decided));
    // Rejected by its own weight, with every coupled switch on.
    auto rejected_by_itself = [&](const ClosureDecision& d) {
      if (d.accepted || d.own_weight > 0.5) return false;
      const auto coupled = coupled_switches.find(d.id);
      return coupled == coupled_switches.end() ||
             std::all_of(coupled->second.begin(), coupled->second.end(),
                         [&](SwitchId s) { return psi(graph.switches.at(s).value) > 0.5; });
    };
    Summary times;  // of the refinements
    int iterations = 0;
    for (int round = 0; round < kReadmitRounds; ++round) {
      std::vector<ClosureDecision*> candidates;
      std::vector<const Constraint<PoseT>*> tested;
      for (ClosureDecision& d : out.closures) {
        if (!rejected_by_itself(d) || !by_method(d)) continue;
        candidates.push_back(&d);
        tested.push_back(constraint_of.at(d.id));
      }
      if (candidates.empty()) break;
      const auto start = std::chrono::steady_clock::now();
      Values values;
      FactorGraph map;
      map_factors(map, values, graph.vertices);
      std::vector<double> nis;
      try {
        nis = InnovationChi2<PoseT>(map, values, tested);
      } catch (const std::runtime_error&) {
        // The accepted closures leave the map undetermined: nothing to test against.
      }
      out.readmit_test_time_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      std::vector<ClosureDecision*> passed;
      for (std::size_t i = 0; i < nis.size(); ++i) {
        if (nis[i] <= family_gate) passed.push_back(candidates[i]);
      }
      if (passed.empty()) break;
      const auto decisions_before = out.closures;
      const auto switches_before = graph.switches;
      const auto vertices_before = graph.vertices;
      for (ClosureDecision* d : passed) {
        d->accepted = d->readmitted = true;
        d->weight = d->own_weight = 1.0;
        if (const auto s = switch_of.find(d->id); s != switch_of.end()) graph.switches.at(s->second).value = 1.0;
      }
      Summary refined = refine(false);
      times.AddTimes(refined);
      iterations += refined.iterations;
      if (!refined.IsUsable()) {  // the last map and its decisions stand
        out.closures = decisions_before;
        graph.switches = switches_before;
        graph.vertices = vertices_before;
        break;
      }
      out.readmitted += passed.size();
      out.readmission = refined;
    }
    if (out.readmission) out.readmission->SetTimes(times);
    end_stage("readmit", iterations);
  }
  for (const ClosureDecision& d : out.closures) (d.accepted ? out.accepted : out.rejected) += 1;
  // The decisions travel with the graph, so that a reader of the written
  // file counts a closure as this solve did.
  if (options.method != RobustMethod::kNone) {
    std::map<ClosureId, RobustDecision> decided;
    for (const ClosureDecision& d : out.closures) decided.emplace(d.id, RobustDecision{d.accepted, d.weight});
    for (auto& c : graph.constraints) {
      const auto it = decided.find(c.id);
      c.decision = it == decided.end() ? std::nullopt : std::optional<RobustDecision>(it->second);
    }
  }
  out.chi2 = GraphChi2(graph);
  out.chordal_cost = GraphChordalCost(graph);
  out.graph = std::move(graph);
  end_stage("costs", 0);
  return out;
}

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
  Validate(options);
  return std::visit([&](const auto& g) { return Run(g, options); }, graph);
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
