#include "experiments/inference_sweep.h"

#include <algorithm>
#include <stdexcept>
#include <utility>

#include "mapping/map_dataset.h"

namespace catgraph {

std::vector<InferenceSweepCell> RunInferenceSweep(const Dataset& d, const std::vector<Observation>& observations,
                                                  const ObservationModel& model, const InferenceSweepOptions& o,
                                                  const std::function<void(std::size_t, std::size_t)>& progress) {
  if (!(o.false_threshold_m > 0.0)) throw std::invalid_argument("InferenceSweepOptions: false_threshold_m must be > 0");
  if (!d.HasGroundTruth()) throw std::invalid_argument("the inference sweep needs ground truth");
  const Trajectory2 truth = mapping::TruthAtFrames(d);
  LocalizationOptions options = o.front_end;
  std::vector<InferenceSweepCell> cells;
  const std::size_t total = o.d_tot_m.size() * o.d_loc_m.size();
  for (const double t : o.d_tot_m) {
    for (const double l : o.d_loc_m) {
      options.filter.inference.enabled = true;
      options.filter.inference.total_validation_m = t;
      options.filter.inference.local_validation_m = l;
      InferenceSweepCell cell;
      cell.d_tot_m = t;
      cell.d_loc_m = l;
      LocalizationResult r = Localize(d, observations, model, options);
      if (o.back_end) {
        mapping::MappingResult mapped = mapping::SolveWithFeedback(d, observations, model, std::move(r),
                                                                   o.back_end->optimizer, o.back_end->hierarchy, truth);
        const std::vector<double>& kept = mapped.outcome.by_kind.at(ClosureKind::kOdometryInferred).accepted_errors;
        cell.false_accepted = static_cast<std::size_t>(
            std::count_if(kept.begin(), kept.end(), [&o](double e) { return e > o.false_threshold_m; }));
        cell.reruns = mapped.reruns;
        r = std::move(mapped.front);
      }
      double sum_false = 0.0, sum = 0.0;
      for (const auto& c : r.closures) {
        if (c.kind != ClosureKind::kOdometryInferred) continue;
        ++cell.inferred;
        sum += c.error_m;
        cell.largest_error_m = std::max(cell.largest_error_m, c.error_m);
        if (c.error_m > o.false_threshold_m) ++cell.wrong, sum_false += c.error_m;
      }
      cell.mean_false_error_m = cell.wrong > 0 ? sum_false / cell.wrong : 0.0;
      cell.mean_error_m = cell.inferred > 0 ? sum / cell.inferred : 0.0;
      cell.discarded = TotalPathDiscards(r);
      cell.dropped = r.discarded_inferences.size() - cell.discarded;
      cells.push_back(cell);
      if (progress) progress(cells.size(), total);
    }
  }
  return cells;
}

}  // namespace catgraph
