// The front-end stage of the command line, shared by `catgraph localize`,
// `inference-sweep` and `map`: its options, the default vocabulary, the
// filter run with progress bars, and what it writes (hypotheses.csv,
// closures.json, discarded_inferences.json, graph.g2o, localization.png/svg)
// and prints. docs/cli.md documents the files.
#ifndef CATGRAPH_APPS_LOCALIZATION_REPORT_H_
#define CATGRAPH_APPS_LOCALIZATION_REPORT_H_

#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "apps/plot/figure.h"
#include "backend/io/dataset.h"
#include "backend/io/output_directory.h"
#include "experiments/false_matches.h"
#include "frontend/localization.h"
#include "mapping/mapper.h"

namespace catgraph {

struct LocalizeCommandOptions {
  std::string dataset, vocabulary, output;
  // Every library option: --preset, then --options FILE, then the flags.
  // `localize` uses the front end's; `map` all of them.
  mapping::MapperOptions pipeline;
  // The flags that set a library option, and the field each sets as the
  // libraries' Validate names it (ValidateOptions).
  std::vector<std::pair<const CLI::Option*, std::string>> option_fields;
  bool quiet = false, overwrite = false;
};

// After parsing: the library's Validate on every option; a field it refuses
// that a flag set is that flag's error (CLI::ValidationError, naming the
// flag), else a std::invalid_argument. The ranges live in the libraries
// alone.
void ValidateOptions(const LocalizeCommandOptions& o);

// options.yaml in `dir`: every option the run used (mapping/options_file.h),
// for --options to run it again.
void WriteOptions(const std::filesystem::path& dir, const LocalizeCommandOptions& o);

// The output folder of `command` run on `o.dataset` (and `o.vocabulary`):
// checked before any work, committed by the caller when every file is in it.
OutputDirectory OpenOutputDirectory(const LocalizeCommandOptions& o, const std::string& command);

// The observation options (--observation, --vocabulary, --words,
// --train-every) on `cmd`.
void AddVocabularyOptions(CLI::App& cmd, LocalizeCommandOptions& o);
// The group of the options a command's --help does not list (they are
// listed in docs/cli.md); AddLocalizationOptions' formatter leaves it out.
inline constexpr const char* kUnlistedGroup = "unlisted";

// The vocabulary and filter options of `localize` (and `map`) on `cmd`:
// --preset and --options first (so that the flags given override them), the
// flags named in `shown` in --help, the others accepted but listed only in
// docs/cli.md (an options file is the place for them).
void AddLocalizationOptions(CLI::App& cmd, LocalizeCommandOptions& o,
                            const std::vector<std::string>& shown = {"--observation", "--vocabulary", "--particles",
                                                                     "--seed", "--no-odometric-inference", "--d-loc",
                                                                     "--d-tot"});

// The shape of injected false visual matches (--false-stretch,
// --false-min-error, --false-max-error) on `cmd`; the count is the caller's.
void AddFalseMatchOptions(CLI::App& cmd, FalseMatchOptions& o);

// `o.vocabulary` if given; otherwise one trained as
// `o.pipeline.observation` says on the dataset's first traversal, the map,
// never on the traversals localised against it.
Vocabulary VocabularyFor(const Dataset& d, const LocalizeCommandOptions& o, std::ostream& out);

// What the filter reads, made once for several runs over a dataset: the
// observation of every frame and the observation model.
struct FrontEndInputs {
  std::vector<Observation> observations;
  std::unique_ptr<ObservationModel> model;
};

// The observation model `o.pipeline.observation` and every frame's observation:
// FAB-MAP on the vocabulary (VocabularyFor), or the holistic model
// calibrated on the first traversal; with progress bars unless `o.quiet`
// (which also shows the filter's progress in later runs with
// `o.pipeline.front_end`).
FrontEndInputs PrepareFrontEnd(const Dataset& d, LocalizeCommandOptions& o, std::ostream& out);

// PrepareFrontEnd, then CAT-Graph (and CAT-Graph+) over the dataset.
LocalizationResult RunLocalization(const Dataset& d, LocalizeCommandOptions& o, std::ostream& out);

// The dataset's floor plan (meta.json's walls) as one segments series; no
// points when it has none.
plot::Series WallsSeries(const Dataset& d, std::string label, plot::Color color, double width_pt);

// The CAT-Graph+ paper's Figs. 7, 8 and 11: the hypothesis per frame, and
// the error of every closure per frame.
plot::Figure LocalizationFigure(const Dataset& d, const LocalizationResult& r, double threshold);

// The observation model as report.json and observation.json record it: its
// name, new-place offset and, for the holistic model, its options and
// calibration.
nlohmann::ordered_json ObservationJson(const ObservationSummary& observation);

// One closures.json entry: id, frame, matched_frame, kind, hypothesis,
// relative_pose, error_m, and parents for inferred closures.
nlohmann::ordered_json ClosureJson(const LoopClosure& closure);

// hypotheses.csv, closures.json, discarded_inferences.json, observation.json,
// graph.g2o and localization.png/svg in `dir` (created), each written atomically.
void WriteLocalization(const std::filesystem::path& dir, const Dataset& d, const LocalizationResult& r,
                       double closure_threshold);

// Closures by kind with their errors, and per traversal how many frames
// closed inside and outside the changed regions.
void PrintLocalizationSummary(const Dataset& d, const LocalizationResult& r, bool odometric_inference,
                              std::ostream& out);

// `value` with printf's `format`; empty for NaN.
std::string Number(double value, const char* format = "%.4f");

}  // namespace catgraph

#endif  // CATGRAPH_APPS_LOCALIZATION_REPORT_H_
