// The subcommands of `catgraph`. Each Add*Command registers its options and a
// callback on `app`; the callback writes its report to `out` and throws
// FileError or std::invalid_argument on bad input, which main() turns into a
// one-line message and a non-zero exit status.
#ifndef CATGRAPH_APPS_COMMANDS_H_
#define CATGRAPH_APPS_COMMANDS_H_

#include <ostream>
#include <string>

#include <CLI/CLI.hpp>

#include "backend/io/graph_io.h"

namespace catgraph {

void AddInfoCommand(CLI::App& app, std::ostream& out);
void AddGenerateGraphCommand(CLI::App& app, std::ostream& out);
void AddOptimizeCommand(CLI::App& app, std::ostream& out);
void AddInjectCommand(CLI::App& app, std::ostream& out);
void AddEvaluateCommand(CLI::App& app, std::ostream& out);
void AddExportCommand(CLI::App& app, std::ostream& out);
void AddSweepCommand(CLI::App& app, std::ostream& out);
void AddSimulateCommand(CLI::App& app, std::ostream& out);
void AddConvertCommand(CLI::App& app, std::ostream& out);
void AddImportCommand(CLI::App& app, std::ostream& out);
void AddPlotDatasetCommand(CLI::App& app, std::ostream& out);
void AddVocabularyCommand(CLI::App& app, std::ostream& out);
void AddLocalizeCommand(CLI::App& app, std::ostream& out);
void AddInferenceSweepCommand(CLI::App& app, std::ostream& out);
void AddEvidenceCommand(CLI::App& app, std::ostream& out);
void AddSadMatchCommand(CLI::App& app, std::ostream& out);
void AddMapCommand(CLI::App& app, std::ostream& out);
void AddDemoCommand(CLI::App& app, std::ostream& out);
void AddHierarchyExperimentCommand(CLI::App& app, std::ostream& out);

// The largest --threads and --jobs: more threads than this buy nothing on
// any machine catgraph runs on, and each costs a stack.
inline constexpr int kMaxThreads = 256;

// The --overwrite flag of every command that writes an output folder.
void AddOverwriteFlag(CLI::App& command, bool& overwrite);

// The --format option every graph-reading command takes.
void AddGraphFormatOption(CLI::App& command, std::string& format);

// Reads the graph a command was given, `format` as --format takes it.
GraphFile ReadCommandGraph(const std::string& path, const std::string& format);
// Writes the note a command prints when the reader left out edges from a
// vertex to itself, "note: PATH: 2 edges from a vertex to itself left out, as
// g2o does (lines 5, 9)", and nothing when there were none.
void WriteSelfEdgeNote(std::ostream& out, const std::string& path, const GraphFile& file);

// Builds the whole command-line interface, writing reports to `out`.
void AddAllCommands(CLI::App& app, std::ostream& out);

// Runs `catgraph` with `args` (args[0] is the program name); returns the exit
// status. Reports go to `out`, errors to `err`. main() and the tests share it.
int RunCatgraph(int argc, const char* const* argv, std::ostream& out, std::ostream& err);

}  // namespace catgraph

#endif  // CATGRAPH_APPS_COMMANDS_H_
