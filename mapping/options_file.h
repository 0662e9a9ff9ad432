// Every option of the pipeline in one YAML file, shaped as MapperOptions:
//
//   front_end:
//     filter:             # CatGraphOptions: Table I at the top level ...
//       num_particles: 1000
//       recognition: {closure_min_evidence: 0.2, ...}   # ... catgraph's additions nested
//       new_place: {...}
//       gate: {...}
//       inference: {...}
//     graph_uncertainty: {...}   # PoseGraphUncertainty
//   back_end: {method: switchable, gate: {...}, refinement: {...}, ...}   # PoseGraphOptimizerOptions
//   hierarchy: {policy: cascade, max_rounds: 50}
//   online: {solve: true, max_iterations: 3}
//
// A file names any subset of the keys; the others keep the values they had.
// `catgraph localize` and `map` read one with --options and write the
// options a run used to options.yaml beside its results, which reads back
// to the same options (docs/file-formats.md "Options files").
#ifndef CATGRAPH_MAPPING_OPTIONS_FILE_H_
#define CATGRAPH_MAPPING_OPTIONS_FILE_H_

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "mapping/mapper.h"

namespace catgraph::mapping {

// Starting points for the options: catgraph's defaults, or the CAT-Graph+
// paper's filter exactly (CatGraphOptions::Paper(); the back end, which the
// paper leaves to future work, keeps its defaults).
enum class OptionsPreset { kDefault, kPaper };
std::string_view ToString(OptionsPreset preset);
std::optional<OptionsPreset> OptionsPresetFromString(std::string_view text);  // "default", "paper"
std::vector<std::string> OptionsPresetNames();
MapperOptions PresetOptions(OptionsPreset preset);

// Reads `text` (YAML, from `source`, named in errors) onto `options`: every
// key it holds replaces that field. Then validates every part (the
// libraries' Validate). Throws FileError naming the source, the line and
// what was expected: an unknown key (with the keys its section knows), a
// value of the wrong type, a value out of range.
void ReadOptions(const std::string& text, const std::string& source, MapperOptions& options);
// The same from a file.
void ReadOptionsFile(const std::filesystem::path& path, MapperOptions& options);

// Which of `fields` (dotted paths as the libraries' Validate messages name
// them: "new_place.stay_fraction", "max_iterations") `message` names as a
// whole word, the longest if several; empty if none.
std::string FieldNamedBy(const std::string& message, const std::vector<std::string>& fields);

// Every option as YAML, in the layout above; ReadOptions of it gives the
// same options back (numbers are written to round trip).
std::string OptionsYaml(const MapperOptions& options);

}  // namespace catgraph::mapping

#endif  // CATGRAPH_MAPPING_OPTIONS_FILE_H_
