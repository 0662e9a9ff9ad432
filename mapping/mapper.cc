#include "mapping/mapper.h"

#include <chrono>
#include <stdexcept>
#include <string>
#include <utility>

namespace catgraph::mapping {

PoseGraphOptimizerOptions OnlineSolveOptions(const PoseGraphOptimizerOptions& back_end, int max_iterations) {
  PoseGraphOptimizerOptions online = back_end;
  online.initial_guess = InitialGuess::kFile;
  online.gate.estimate_noise_scale = false;
  online.gate.narrow = false;
  online.refinement.enabled = false;
  online.readmission.enabled = false;
  online.solver.max_iterations = max_iterations;
  return online;
}

void Validate(const MapperOptions& options) {
  Validate(options.observation);
  Validate(options.front_end);
  Validate(options.back_end);
  Validate(options.hierarchy);
  CheckHierarchyForFrontEnd(options.hierarchy, options.back_end);
  if (options.online_max_iterations < 1) {
    throw std::invalid_argument("MapperOptions: online_max_iterations (online.max_iterations) must be >= 1, not " +
                                std::to_string(options.online_max_iterations));
  }
}

Mapper::Mapper(const ObservationModel& model, MapperOptions options)
    : options_(std::move(options)),
      online_(OnlineSolveOptions(options_.back_end, options_.online_max_iterations)),
      localizer_(model, options_.front_end) {
  Validate(options_);
  Validate(online_);
  if (OnlineBackEnd::Supports(online_, options_.hierarchy)) incremental_.emplace(online_, options_.hierarchy);
}

FrameResult Mapper::AddFrame(const FrameInput& frame, const Observation& z) {
  const LocalizationResult& r = localizer_.result();
  const std::size_t closures = r.closures.size(), discarded = r.discarded_inferences.size();
  FrameResult out;
  out.localization = localizer_.AddFrame(frame, z);
  out.closures.assign(r.closures.begin() + static_cast<long>(closures), r.closures.end());
  out.discarded.assign(r.discarded_inferences.begin() + static_cast<long>(discarded), r.discarded_inferences.end());
  if (options_.solve_online && !out.closures.empty()) out.solve = SolveOnline();
  return out;
}

Trajectory2 Mapper::Map() const {
  Trajectory2 map;
  // The last solved frame: its solved pose and its odometry pose.
  std::optional<std::pair<Pose2, Pose2>> anchor;
  for (const auto& [id, vertex] : front_end().graph.vertices) {
    const Pose2& odometry = *vertex.pose;
    if (const auto solved = solved_.find(id); solved != solved_.end()) {
      map.emplace_hint(map.end(), id, solved->second);
      anchor.emplace(solved->second, odometry);
    } else {
      map.emplace_hint(map.end(), id, anchor ? anchor->first * anchor->second.Between(odometry) : odometry);
    }
  }
  return map;
}

OnlineSolve Mapper::SolveOnline() {
  const auto start = std::chrono::steady_clock::now();
  Summary summary;
  OnlineSolve out;
  if (incremental_) {
    const OnlineBackEnd::Solve solved = incremental_->Update(front_end().graph);
    summary = solved.summary;
    out.solves = solved.solves;
    out.accepted = static_cast<int>(solved.accepted);
    out.rejected = static_cast<int>(solved.rejected);
    solved_ = incremental_->Poses();
    decisions_ = incremental_->decisions();
  } else {
    PoseGraph2 graph = front_end().graph;
    const Trajectory2 guess = Map();
    for (auto& [id, vertex] : graph.vertices) vertex.pose = guess.at(id);
    const AnyPoseGraph any(std::move(graph));
    const HierarchicalOptimization solved =
        OptimizeWithHierarchy(any, ClosureHierarchy::FromGraph(any), online_, options_.hierarchy);
    const PoseGraphOptimization& result = solved.optimization;
    summary = result.summary;
    out.solves = solved.solves;
    out.accepted = static_cast<int>(result.accepted);
    out.rejected = static_cast<int>(result.rejected);
    solved_ = TrajectoryOf(std::get<PoseGraph2>(result.graph));
    decisions_.clear();
    for (const ClosureDecision& c : result.closures) decisions_.emplace(c.id, c);
  }
  if (!summary.IsUsable()) throw std::runtime_error("Mapper: the online solve failed: " + summary.message);
  out.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  out.iterations = summary.iterations;
  return out;
}

MapOutcome Mapper::Solve(const Trajectory2& truth) const {
  return SolveMap(front_end(), options_.back_end, options_.hierarchy, truth);
}

}  // namespace catgraph::mapping
