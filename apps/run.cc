#include <exception>
#include <stdexcept>

#include "apps/commands.h"
#include "backend/io/file_error.h"

namespace catgraph {

void AddGraphFormatOption(CLI::App& command, std::string& format) {
  command.add_option("--format", format, "Input format; auto decides from the tags (and .graph for TORO)")
      ->check(CLI::IsMember({"auto", "g2o", "toro", "isam"}))
      ->capture_default_str();
}

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
    err << "catgraph: " << PrintableText(e.what()) << "\nRun 'catgraph --help' for the commands and options.\n";
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
