// catgraph evidence DATASET -o OUT/ [--vocabulary V] [--offsets ...] [--relative ...]
#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "apps/commands.h"
#include "apps/localization_report.h"
#include "backend/io/atomic_file.h"
#include "backend/io/dataset.h"
#include "backend/io/file_error.h"
#include "experiments/evidence.h"

namespace catgraph {
namespace {

struct EvidenceCommandOptions {
  LocalizeCommandOptions base;
  EvidenceOptions evidence;
  std::vector<double> offsets = {0.0, 15.0, 30.0, 45.0};
  std::vector<double> relative = {0.0, 0.1, 0.2, 0.25, 0.3};
};

// The p-quantile (nearest rank) of `values`; NaN when empty.
double Quantile(std::vector<double> values, double p) {
  if (values.empty()) return std::nan("");
  std::sort(values.begin(), values.end());
  const auto i = static_cast<std::size_t>(p * static_cast<double>(values.size() - 1) + 0.5);
  return values[std::min(i, values.size() - 1)];
}

void QuantileRows(const std::vector<FrameEvidence>& frames, const std::string& label, std::ostream& md) {
  const std::vector<std::pair<const char*, std::function<double(const FrameEvidence&)>>> columns = {
      {"self-evidence", [](const FrameEvidence& e) { return e.self; }},
      {"true place", [](const FrameEvidence& e) { return e.true_place; }},
      {"best near place", [](const FrameEvidence& e) { return e.near; }},
      {"best far place", [](const FrameEvidence& e) { return e.far; }},
      {"true place / self", [](const FrameEvidence& e) { return e.true_place / e.self; }},
      {"best near place / self", [](const FrameEvidence& e) { return e.near / e.self; }},
  };
  for (const auto& [name, value] : columns) {
    std::vector<double> v;
    for (const FrameEvidence& e : frames) {
      const double x = value(e);
      if (std::isfinite(x)) v.push_back(x);
    }
    md << "| " << label << " | " << name << " | " << v.size();
    for (const double p : {0.05, 0.25, 0.5, 0.75, 0.95}) md << " | " << Number(Quantile(v, p), "%.2f");
    md << " | " << Number(v.empty() ? std::nan("") : *std::max_element(v.begin(), v.end()), "%.2f") << " |\n";
  }
}

void RunEvidence(EvidenceCommandOptions& o, std::ostream& out) {
  ValidateOptions(o.base);
  OutputDirectory output = OpenOutputDirectory(o.base, "evidence");
  const Dataset d = ReadDataset(o.base.dataset);
  if (!d.HasGroundTruth()) throw FileError(o.base.dataset, 0, "evidence needs ground truth (groundtruth.csv)");
  const std::vector<int> traversals = d.Traversals();
  if (traversals.size() < 2) throw FileError(o.base.dataset, 0, "evidence needs a second traversal to query");
  for (const double r : o.relative) {
    if (!(r >= 0.0 && r < 1.0)) throw std::invalid_argument("--relative: expected values in [0, 1)");
  }
  try {
    Validate(o.evidence);  // before the features are extracted
  } catch (const std::invalid_argument&) {
    throw std::invalid_argument("--true-radius, --near-min, --near-max: expected 0 < true radius <= near min < near max");
  }
  const FrontEndInputs in = PrepareFrontEnd(d, o.base, out);
  const std::vector<Pose2> truth = PosesAtFrames(d, d.ground_truth);
  std::vector<bool> changed;
  std::vector<int> map_frames, query_frames;
  for (std::size_t i = 0; i < d.frames.size(); ++i) {
    changed.push_back(d.frames[i].changed);
    (d.frames[i].traversal == traversals.front() ? map_frames : query_frames).push_back(static_cast<int>(i));
  }
  const std::vector<FrameEvidence> evidence =
      MeasureEvidence(*in.model, in.observations, truth, changed, map_frames, query_frames, o.evidence);

  std::ostringstream csv, md;
  csv << "frame,words,changed,self,true_place,near,far\n";
  for (const FrameEvidence& e : evidence) {
    csv << e.frame << ',' << e.words << ',' << (e.changed ? 1 : 0) << ',' << Number(e.self, "%.3f") << ','
        << Number(e.true_place, "%.3f") << ',' << Number(e.near, "%.3f") << ',' << Number(e.far, "%.3f") << '\n';
  }
  std::vector<FrameEvidence> unchanged, in_changed;
  for (const FrameEvidence& e : evidence) (e.changed ? in_changed : unchanged).push_back(e);
  md << "Evidence over new place (" << in.model->Name() << " model's nats) of the query frames (traversals after the first) against the "
        "map frames (the first): true place within "
     << Number(o.evidence.true_radius_m, "%.1f") << " m, near places " << Number(o.evidence.near_min_m, "%.1f")
     << "-" << Number(o.evidence.near_max_m, "%.1f") << " m away, far beyond.\n\n"
     << "| query frames | quantity | frames | p5 | p25 | median | p75 | p95 | max |\n|---|---|---|---|---|---|---|---|---|\n";
  QuantileRows(unchanged, "unchanged", md);
  if (!in_changed.empty()) QuantileRows(in_changed, "changed", md);
  md << "\nUnchanged query frames with a true place: how often the true place (first figure) and the best near "
        "place (second) score over the offset constant + relative x self-evidence.\n\n| constant \\ relative |";
  for (const double r : o.relative) md << ' ' << Number(r, "%.2f") << " |";
  md << "\n|---|";
  for (std::size_t i = 0; i < o.relative.size(); ++i) md << "---|";
  md << '\n';
  for (const double c : o.offsets) {
    md << "| " << Number(c, "%.0f") << " |";
    for (const double r : o.relative) {
      const OffsetSeparation s = SeparationAt(unchanged, c, r);
      md << ' ' << Number(100.0 * s.true_over, "%.1f") << " % / " << Number(100.0 * s.near_over, "%.1f") << " % |";
    }
    md << '\n';
  }
  WriteFileAtomically(output.path() / "evidence.csv", [&](std::ostream& f) { f << csv.str(); });
  WriteFileAtomically(output.path() / "summary.md", [&](std::ostream& f) { f << md.str(); });
  output.Commit();
  out << md.str();
}

}  // namespace

void AddEvidenceCommand(CLI::App& app, std::ostream& out) {
  auto o = std::make_shared<EvidenceCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "evidence",
      "How well the observation model tells the true place from its look-alikes, frame by frame against ground truth: each "
      "query frame's self-evidence and the evidence of its true, near and far places (evidence.csv), and how "
      "often each scores over a grid of new-place offsets (summary.md). The measurement behind "
      "--new-place-offset and --new-place-stay-relative-offset: docs/frontend.md.");
  cmd->add_option("dataset", o->base.dataset, "Dataset directory (with ground truth and two traversals)")->required();
  cmd->add_option("-o,--output", o->base.output, "Output directory")->required();
  AddVocabularyOptions(*cmd, o->base);
  cmd->add_option("--offsets", o->offsets, "Constant offsets of the grid (nats)")->delimiter(',')->capture_default_str();
  cmd->add_option("--relative", o->relative, "Relative offsets of the grid (fractions of the self-evidence)")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--true-radius", o->evidence.true_radius_m, "The true place: map frames nearer than this (m)")
      ->capture_default_str();
  cmd->add_option("--near-min", o->evidence.near_min_m, "Near places: from this far (m)")->capture_default_str();
  cmd->add_option("--near-max", o->evidence.near_max_m, "... to this far (m); farther ones are far")
      ->capture_default_str();
  cmd->add_option("--threads", o->base.pipeline.front_end.threads, "Feature-extraction threads (0: every core)")
      ->check(CLI::Range(0, kMaxThreads))
      ->capture_default_str();
  cmd->add_flag("--quiet", o->base.quiet, "No progress bar");
  AddOverwriteFlag(*cmd, o->base.overwrite);
  cmd->callback([o, &out] { RunEvidence(*o, out); });
}

}  // namespace catgraph
