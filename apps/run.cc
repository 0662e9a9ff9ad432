#include <algorithm>
#include <exception>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "apps/commands.h"
#include "backend/io/file_error.h"

namespace catgraph {

void AddGraphFormatOption(CLI::App& command, std::string& format) {
  command.add_option("--format", format, "Input format; auto decides from the tags (and .graph for TORO)")
      ->check(CLI::IsMember({"auto", "g2o", "toro", "isam"}))
      ->capture_default_str();
}

GraphFile ReadCommandGraph(const std::string& path, const std::string& format) {
  ReadGraphOptions options;
  options.format = *GraphFormatFromString(format);
  return ReadGraphFile(path, options);
}

void WriteSelfEdgeNote(std::ostream& out, const std::string& path, const GraphFile& file) {
  const std::vector<int>& lines = file.self_edge_lines;
  if (lines.empty()) return;
  out << "note: " << path << ": " << lines.size() << (lines.size() == 1 ? " edge" : " edges")
      << " from a vertex to itself left out, as g2o does (line" << (lines.size() == 1 ? " " : "s ");
  constexpr std::size_t kNamed = 10;
  for (std::size_t k = 0; k < std::min(lines.size(), kNamed); ++k) out << (k ? ", " : "") << lines[k];
  out << (lines.size() > kNamed ? ", ...)\n" : ")\n");
}

namespace {

// Levenshtein distance, for suggestions.
std::size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

// The name nearest to `typed`, when it is within a third of its length
// (at least one edit): "optimze" -> "optimize", "--particels" -> "--particles".
std::optional<std::string> Nearest(const std::string& typed, const std::vector<std::string>& names) {
  std::optional<std::string> best;
  std::size_t best_distance = std::max<std::size_t>(1, typed.size() / 3) + 1;
  for (const std::string& name : names) {
    const std::size_t d = EditDistance(typed, name);
    if (d < best_distance) best = name, best_distance = d;
  }
  return best;
}

// For arguments CLI11 did not expect: the command or option meant, from the
// innermost command given.
std::string Suggestions(const CLI::App& app) {
  const CLI::App* command = &app;
  while (!command->get_subcommands().empty()) command = command->get_subcommands().front();
  std::vector<std::string> commands, options;
  for (const CLI::App* sub : command->get_subcommands({})) commands.push_back(sub->get_name());
  for (const CLI::Option* option : command->get_options()) {
    for (const std::string& name : option->get_lnames()) options.push_back("--" + name);
  }
  std::string text;
  for (const std::string& extra : app.remaining(/*recurse=*/true)) {
    const std::optional<std::string> meant =
        Nearest(extra.substr(0, extra.find('=')), extra.starts_with("-") ? options : commands);
    if (meant) text += (text.empty() ? " (did you mean " : ", ") + ("'" + *meant + "'");
  }
  return text.empty() ? text : text + "?)";
}

}  // namespace

void AddOverwriteFlag(CLI::App& command, bool& overwrite) {
  command.add_flag("--overwrite", overwrite,
                   "Write into an output folder that holds other files (files of the same name are replaced, "
                   "nothing else is touched); without it such a folder is refused. docs/cli.md \"Outputs\"");
}

void AddAllCommands(CLI::App& app, std::ostream& out) {
  app.require_subcommand(1);
  app.set_version_flag("--version", "catgraph 0.1.0");
  AddInfoCommand(app, out);
  AddGenerateGraphCommand(app, out);
  AddOptimizeCommand(app, out);
  AddInjectCommand(app, out);
  AddEvaluateCommand(app, out);
  AddSweepCommand(app, out);
  AddExportCommand(app, out);
  AddSimulateCommand(app, out);
  AddConvertCommand(app, out);
  AddImportCommand(app, out);
  AddPlotDatasetCommand(app, out);
  AddVocabularyCommand(app, out);
  AddLocalizeCommand(app, out);
  AddInferenceSweepCommand(app, out);
  AddEvidenceCommand(app, out);
  AddSadMatchCommand(app, out);
  AddMapCommand(app, out);
  AddDemoCommand(app, out);
  AddHierarchyExperimentCommand(app, out);
}

int RunCatgraph(int argc, const char* const* argv, std::ostream& out, std::ostream& err) {
  CLI::App app{
      "catgraph: mapping in environments whose appearance changes.\n"
      "CAT-Graph+ front end, robust pose-graph back end, experiments and export.",
      "catgraph"};
  AddAllCommands(app, out);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp&) {
    out << app.help();  // delegates to the selected subcommand
    return 0;
  } catch (const CLI::CallForAllHelp&) {
    out << app.help("", CLI::AppFormatMode::All);
    return 0;
  } catch (const CLI::CallForVersion&) {
    out << "catgraph 0.1.0\n";
    return 0;
  } catch (const CLI::ParseError& e) {
    // A first word that names no command: say so, rather than CLI11's "a
    // subcommand is required".
    const std::vector<std::string> extras = app.remaining(/*recurse=*/true);
    const bool unknown_command = app.get_subcommands().empty() && !extras.empty() && !extras.front().starts_with("-");
    const std::string what = unknown_command ? "unknown command '" + extras.front() + "'" : std::string(e.what());
    err << "catgraph: " << PrintableText(what) << PrintableText(Suggestions(app)) << "\nRun 'catgraph --help' for the commands and options.\n";
    return 2;
  } catch (const FileError& e) {
    err << "catgraph: error: " << PrintableText(e.what()) << '\n';
    return 1;
  } catch (const std::invalid_argument& e) {
    err << "catgraph: error: " << PrintableText(e.what()) << '\n';
    return 1;
  } catch (const std::runtime_error& e) {
    err << "catgraph: error: " << PrintableText(e.what()) << '\n';
    return 1;
  } catch (const std::exception& e) {
    err << "catgraph: internal error: " << PrintableText(e.what()) << '\n';
    return 3;
  }
  return 0;
}

}  // namespace catgraph
