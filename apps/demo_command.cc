// catgraph demo [-o OUT] [--scenario NAME|FILE] [--hierarchy H] [--quiet]
//
// Everything on simulated data in a few minutes: simulate office-change (the
// furniture of one corridor moved before the second traversal) or another
// scenario, map it with `catgraph map`, and print what came of it. The same
// commands a user would type, run in-process.
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "apps/commands.h"
#include "apps/localization_report.h"
#include "backend/io/file_error.h"
#include "simulation/scenario.h"

namespace catgraph {
namespace {

struct DemoOptions {
  std::string output = "catgraph-demo";
  std::string scenario = "office-change";
  std::string hierarchy = "cascade";
  bool quiet = false;
};

void RunStep(const std::vector<std::string>& args, std::ostream& out) {
  std::vector<const char*> argv = {"catgraph"};
  std::string line = "$ catgraph";
  for (const std::string& a : args) {
    argv.push_back(a.c_str());
    line += " " + a;
  }
  out << line << '\n';
  std::ostringstream err;
  if (RunCatgraph(static_cast<int>(argv.size()), argv.data(), out, err) != 0) {
    std::string why = err.str();
    while (!why.empty() && why.back() == '\n') why.pop_back();
    throw std::runtime_error("demo step failed: " + line + " -- " + why);
  }
}

void RunDemo(const DemoOptions& o, std::ostream& out) {
  // Loaded here too, so that a bad scenario file fails before anything is
  // written. The data folder is named after the built-in scenario or the
  // file (its stem), never after a name inside the file.
  const Scenario scenario = LoadScenario(o.scenario);
  const std::string name = std::filesystem::path(o.scenario).stem().string();
  const std::filesystem::path dir(o.output);
  const std::string data = (dir / name).string(), map = (dir / "map").string();
  std::vector<std::string> quiet;
  if (o.quiet) quiet.push_back("--quiet");
  std::vector<std::string> simulate = {"simulate", "--scenario", o.scenario, "-o", data};
  simulate.insert(simulate.end(), quiet.begin(), quiet.end());
  RunStep(simulate, out);
  std::vector<std::string> mapping = {"map", data, "-o", map, "--hierarchy", o.hierarchy};
  mapping.insert(mapping.end(), quiet.begin(), quiet.end());
  RunStep(mapping, out);

  const std::filesystem::path report_path = dir / "map" / "report.json";
  std::ifstream in(report_path);
  const nlohmann::json report = nlohmann::json::parse(in);
  const std::size_t traversals = scenario.traversals.size();
  out << "\ncatgraph demo: " << name << ", " << report.at("frames").get<int>() << " frames over "
      << (traversals == 1 ? std::string("one traversal")
                          : (traversals == 2 ? std::string("two") : std::to_string(traversals)) + " traversals")
      << '\n';
  for (const char* kind : {"visual", "inferred"}) {
    const nlohmann::json& k = report.at("closures_by_kind").at(kind);
    out << "  " << kind << " closures: " << k.at("count").get<int>() << ", " << k.at("accepted").get<int>()
        << " accepted";
    if (!k.at("error_mean_m").is_null()) {
      out << "; error against ground truth mean " << Number(k.at("error_mean_m").get<double>(), "%.3f")
          << " m, max " << Number(k.at("error_max_m").get<double>(), "%.3f") << " m";
    }
    out << '\n';
  }
  out << "  turned off by the " << o.hierarchy << " hierarchy: " << report.at("turned_off").size() << '\n';
  out << "  ATE (RMSE after alignment): odometry alone "
      << Number(report.at("ate_odometry").at("rmse_m").get<double>(), "%.3f") << " m, corrected map "
      << Number(report.at("ate_corrected").at("rmse_m").get<double>(), "%.3f") << " m\n";
  out << "  pictures: " << (dir / "map" / "index.html").string() << " (map.png: the map, Fig. 10; "
      << "localization.png: hypothesis and closure error per frame, Figs. 7, 8, 11)\n";
}

}  // namespace

void AddDemoCommand(CLI::App& app, std::ostream& out) {
  auto o = std::make_shared<DemoOptions>();
  CLI::App* cmd = app.add_subcommand(
      "demo",
      "Simulate office-change (furniture moved before the second traversal), map it with catgraph map, and "
      "summarise: closures by kind, their errors, ATE before and after, where the pictures are.");
  cmd->add_option("-o,--output", o->output, "Output directory (the scenario's data and map/ inside)")
      ->capture_default_str();
  cmd->add_option("--scenario", o->scenario, "Built-in scenario name or scenario file, as catgraph simulate")
      ->capture_default_str();
  cmd->add_option("--hierarchy", o->hierarchy, "Closure hierarchy policy (as catgraph map)")
      ->check(CLI::IsMember({"cascade", "coupled", "flat"}))
      ->capture_default_str();
  cmd->add_flag("--quiet", o->quiet, "No progress bars");
  cmd->callback([o, &out] { RunDemo(*o, out); });
}

}  // namespace catgraph
