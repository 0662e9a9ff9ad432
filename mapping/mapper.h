// The online mapper: a robot feeds it frame by frame (time, odometry,
// image or its observation) and gets back, per frame, where it is on the
// map, the closures made (visual, and the inferences a visual closure
// validated), and, when closures arrived, the corrected map, re-solved from
// the last solution — in the manner of Cartographer's map builder.
//
//   mapping::Mapper mapper(model, options);
//   for (each frame) {
//     const mapping::FrameResult r = mapper.AddFrame({time_s, odometry_pose}, observation);
//     for (const LoopClosure& c : r.closures) ...   // new closures, with provenance
//     if (r.solve) ... mapper.Map() ...             // the map corrected with them
//   }
//   const mapping::MapOutcome final = mapper.Solve();  // the full robust solve, as offline
//
// Online solves are a few iterations from the last map (OnlineSolveOptions):
// with switchable constraints (the default) on one problem that grows with
// the graph (OnlineBackEnd), with another method a new solve each time.
// Solve() runs the back end exactly as MapDataset's first solve does, so the
// final map of a streamed dataset equals the offline one. The back end's rejections of visual closures reach CAT-Graph+
// only offline (SolveWithFeedback re-runs the front end with them vetoed);
// online they turn the closures' children off through the hierarchy.
//
// Thread-compatible: one thread feeds a Mapper.
#ifndef CATGRAPH_MAPPING_MAPPER_H_
#define CATGRAPH_MAPPING_MAPPER_H_

#include <map>
#include <optional>
#include <vector>

#include "backend/graph/trajectory.h"
#include "backend/pose_graph_optimizer.h"
#include "frontend/localization.h"
#include "hierarchy/closure_hierarchy.h"
#include "mapping/map_dataset.h"
#include "mapping/online_back_end.h"

namespace catgraph::mapping {

struct MapperOptions {
  // How the frames are observed, for a caller that builds the observation
  // model from a dataset (catgraph map, localize); the Mapper itself takes
  // the model it is given.
  ObservationOptions observation;
  LocalizationOptions front_end;         // CAT-Graph, CAT-Graph+, the pose graph's uncertainty
  PoseGraphOptimizerOptions back_end;    // Solve(); online solves start from it (OnlineSolveOptions)
  HierarchyOptions hierarchy;
  // Re-solve the back end after each frame that made closures; false: only
  // when Solve() is called.
  bool solve_online = true;
  // Iterations an online solve takes at most; >= 1. Each starts from the
  // last one's map, so the map converges over the solves that follow; with
  // fewer than 3 the map seen while driving is worse on every simulated
  // dataset measured (docs/mapping.md).
  int online_max_iterations = 3;
};
// Every part (the libraries' Validate), and a hierarchy the front end's
// graph can take (CheckHierarchyForFrontEnd); throws std::invalid_argument
// naming the first field out of range.
void Validate(const MapperOptions& options);

// The back end's options for online solves: `back_end` from the last
// solution (the file's guess), at most `max_iterations` iterations, the gate
// at the information's own scale and the robust solve's map — without the
// stages that measure the noise, re-decide or re-solve from scratch (noise
// scale, narrowing, refinement, readmission), which the final Solve() runs.
PoseGraphOptimizerOptions OnlineSolveOptions(const PoseGraphOptimizerOptions& back_end, int max_iterations);

// One online solve.
struct OnlineSolve {
  double time_s = 0.0;  // wall clock, the hierarchy's re-solves included
  int iterations = 0;   // of the last solve
  int solves = 1;       // the hierarchy's rounds included
  int accepted = 0, rejected = 0;  // closures so far
};

struct FrameResult {
  FrameLocalization localization;
  std::vector<LoopClosure> closures;          // made at this frame: a visual one, then the inferences it validated
  std::vector<DiscardedInference> discarded;  // inferences discarded or dropped at this frame
  std::optional<OnlineSolve> solve;           // the re-solve these closures caused
};

class Mapper {
 public:
  // `model` must outlive the mapper. Throws std::invalid_argument on options
  // out of range.
  Mapper(const ObservationModel& model, MapperOptions options);
  Mapper(const Mapper&) = delete;
  Mapper& operator=(const Mapper&) = delete;

  // Adds the next frame, vertex front_end().frames.size() of the pose graph.
  // Throws std::runtime_error when an online solve fails.
  FrameResult AddFrame(const FrameInput& frame, const Observation& z);

  // Every frame's pose: the last solve's for the frames it had, each later
  // frame chained to the last of them by odometry; odometry alone before the
  // first solve.
  Trajectory2 Map() const;
  // What the last online solve decided about each closure; empty before it.
  const std::map<ClosureId, ClosureDecision>& decisions() const { return decisions_; }
  // The front end's result so far: frames, closures, the pose graph.
  const LocalizationResult& front_end() const { return localizer_.result(); }

  // The back end on everything so far with options.back_end, from the
  // odometry (not warm-started: the offline pipeline's solve), scored
  // against `truth` (vertex id = frame; may be empty). Throws
  // std::runtime_error when the solver fails.
  MapOutcome Solve(const Trajectory2& truth = {}) const;

 private:
  OnlineSolve SolveOnline();

  MapperOptions options_;
  PoseGraphOptimizerOptions online_;
  Localizer localizer_;
  std::optional<OnlineBackEnd> incremental_;      // when it supports the options
  Trajectory2 solved_;                             // the last online solve's poses
  std::map<ClosureId, ClosureDecision> decisions_;
};

}  // namespace catgraph::mapping

#endif  // CATGRAPH_MAPPING_MAPPER_H_
