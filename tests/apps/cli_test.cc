// The `catgraph` command run in process, exactly as main() runs it.
#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "tests/catch.h"
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "apps/commands.h"
#include "apps/localization_report.h"
#include "apps/plot/figure.h"
#include "experiments/sweep.h"
#include "backend/io/closure_labels.h"
#include "backend/io/dataset.h"
#include "tests/test_support.h"

namespace catgraph {
namespace {

struct Result {
  int status;
  std::string out;
  std::string err;
};

Result Run(const std::vector<std::string>& args) {
  std::vector<const char*> argv = {"catgraph"};
  for (const auto& a : args) argv.push_back(a.c_str());
  std::ostringstream out, err;
  const int status = RunCatgraph(static_cast<int>(argv.size()), argv.data(), out, err);
  return {status, out.str(), err.str()};
}

TEST_CASE("catgraph info --json reports the public keys", "[apps][info]") {
  const Result r = Run({"info", testing::Fixture("vertigo_switchable_2d.g2o").string(), "--json"});
  REQUIRE(r.status == 0);
  const auto j = nlohmann::json::parse(r.out);
  CHECK(j.at("dimension") == 2);
  CHECK(j.at("vertices") == 4);
  CHECK(j.at("edges") == 5);
  CHECK(j.at("odometry_edges") == 3);
  CHECK(j.at("loop_closures") == 2);
  CHECK(j.at("switches") == 1);
  CHECK(j.at("connected") == true);
}

TEST_CASE("info and optimize count the edges from a vertex to itself they leave out and name their lines",
          "[apps][info][optimize]") {
  const auto root = testing::TempDir("self_edges");
  const std::string info = " 1 0 0 1 0 1";
  std::ofstream(root / "self.g2o") << "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nVERTEX_SE2 2 2 0 0\n"
                                   << "EDGE_SE2 0 1 1 0 0" << info << "\nEDGE_SE2 1 1 0 0 0" << info << "\n"
                                   << "EDGE_SE2 1 2 1 0 0" << info << "\nEDGE_SE2 2 2 0 0 0" << info << "\n";
  const std::string file = (root / "self.g2o").string();
  const Result text = Run({"info", file});
  REQUIRE(text.status == 0);
  CHECK(text.out.find("note: " + file + ": 2 edges from a vertex to itself left out, as g2o does (lines 5, 7)") !=
        std::string::npos);
  CHECK(text.out.find("2 odometry, 0 loop closures") != std::string::npos);
  const Result json = Run({"info", file, "--json"});
  REQUIRE(json.status == 0);
  CHECK(nlohmann::json::parse(json.out).at("self_edges_skipped") == 2);
  const Result optimized = Run({"optimize", file, "-o", (root / "out.g2o").string(), "--json"});
  INFO(optimized.err);
  REQUIRE(optimized.status == 0);
  CHECK(nlohmann::json::parse(optimized.out).at("self_edges_skipped") == 2);
  std::filesystem::remove_all(root);
}

TEST_CASE("catgraph info prints a readable summary", "[apps][info]") {
  const Result r = Run({"info", testing::Fixture("small_toro.graph").string()});
  REQUIRE(r.status == 0);
  CHECK(r.out.find("(toro, 2D)") != std::string::npos);
  CHECK(r.out.find("2 odometry, 1 loop closures") != std::string::npos);
  CHECK(r.out.find("connected:     yes") != std::string::npos);
}

TEST_CASE("catgraph info on bad input exits non-zero with one line naming file and line",
          "[apps][info][bad-input]") {
  const auto dir = std::filesystem::temp_directory_path() / "catgraph_cli_test";
  std::filesystem::create_directories(dir);
  const auto bad = dir / "bad.g2o";
  {
    std::ofstream(bad) << "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nEDGE_SE2 0 1 1 0\n";
  }
  const Result r = Run({"info", bad.string()});
  CHECK(r.status == 1);
  CHECK(r.err == "catgraph: error: " + bad.string() +
                     ":3: EDGE_SE2: expected 11 values (i j dx dy dtheta and 6 information "
                     "entries), found 4 (truncated line?)\n");
  CHECK(r.out.empty());
  const Result missing = Run({"info", (dir / "none.g2o").string()});
  CHECK(missing.status == 1);
  CHECK(missing.err.find("none.g2o: no such file") != std::string::npos);
  const Result directory = Run({"info", dir.string()});
  CHECK(directory.status == 1);
  CHECK(directory.err.find("is a directory") != std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST_CASE("catgraph --help and info --help describe the options", "[apps]") {
  const Result top = Run({"--help"});
  CHECK(top.status == 0);
  CHECK(top.out.find("info") != std::string::npos);
  CHECK(top.out.find("generate-graph") != std::string::npos);
  const Result info = Run({"info", "--help"});
  CHECK(info.status == 0);
  CHECK(info.out.find("--json") != std::string::npos);
  CHECK(info.out.find("--format") != std::string::npos);
  const Result unknown = Run({"frobnicate"});
  CHECK(unknown.status == 2);
}

TEST_CASE("catgraph generate-graph writes a graph that info reads back", "[apps][simulation]") {
  const auto dir = std::filesystem::temp_directory_path() / "catgraph_generate_test";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string graph = (dir / "g.g2o").string(), truth = (dir / "t.g2o").string();
  REQUIRE(Run({"generate-graph", "-o", graph, "--truth", truth, "--poses", "200", "--seed", "4"})
              .status == 0);
  const Result r = Run({"info", graph, "--json"});
  REQUIRE(r.status == 0);
  const auto j = nlohmann::json::parse(r.out);
  CHECK(j.at("vertices") == 200);
  CHECK(j.at("odometry_edges") == 199);
  CHECK(j.at("connected") == true);
  CHECK(Run({"generate-graph", "-o", graph, "--poses", "1"}).status == 2);  // out of range: a bad command line
  std::filesystem::remove_all(dir);
}

TEST_CASE("catgraph optimize writes the corrected graph and reports the public keys",
          "[apps][optimize]") {
  const auto dir = std::filesystem::temp_directory_path() / "catgraph_optimize_test";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string graph = (dir / "g.g2o").string(), out = (dir / "o.g2o").string();
  const std::string report = (dir / "r.json").string();
  REQUIRE(Run({"generate-graph", "-o", graph, "--poses", "150", "--seed", "5"}).status == 0);
  const Result r = Run({"optimise", graph, "-o", out, "--json", "--report", report});
  REQUIRE(r.status == 0);
  const auto j = nlohmann::json::parse(r.out);
  for (const char* key : {"iterations", "initial_cost", "final_cost", "chi2", "time_s", "accepted",
                          "rejected"}) {
    CHECK(j.contains(key));
  }
  CHECK(j.at("final_cost").get<double>() < j.at("initial_cost").get<double>());
  // final_cost is where the text report ends (the last stage), not the
  // robust solve's, on a graph with outliers that every stage touches.
  const std::string spoiled = (dir / "s.g2o").string();
  REQUIRE(Run({"inject", graph, "-o", spoiled, "--outliers", "20"}).status == 0);
  const Result text = Run({"optimize", spoiled, "-o", out});
  const Result json = Run({"optimize", spoiled, "-o", out, "--json"});
  REQUIRE(text.status == 0);
  REQUIRE(json.status == 0);
  const auto stages = nlohmann::json::parse(json.out);
  REQUIRE(stages.at("refined") == true);
  const std::size_t last_arrow = text.out.rfind("-> ");
  REQUIRE(last_arrow != std::string::npos);
  CHECK(stages.at("final_cost").get<double>() == Approx(std::stod(text.out.substr(last_arrow + 3))).epsilon(1e-5));
  CHECK(stages.at("robust_final_cost").get<double>() != stages.at("final_cost").get<double>());
  // Each stage's wall-clock time and iterations, in the order they ran; they
  // hold every solve's time and the initial guess's.
  std::vector<std::string> names;
  double wall = 0.0;
  for (const auto& s : stages.at("stages")) {
    names.push_back(s.at("stage").get<std::string>());
    wall += s.at("time_s").get<double>();
    if (s.at("stage") == "robust_solve") CHECK(s.at("iterations") == stages.at("iterations"));
    if (s.at("stage") == "refine") CHECK(s.at("iterations") == stages.at("refine_iterations"));
    if (s.at("stage") == "initial_guess") CHECK(s.at("time_s") == stages.at("initial_guess_time_s"));
  }
  // Narrowing measures the accepted closures' noise and, finding it as
  // stated, runs no second solve here, so readmission runs.
  CHECK(names == std::vector<std::string>{"noise_scale", "initial_guess", "robust_solve", "narrow", "refine",
                                          "readmit", "costs"});
  CHECK(stages.at("wall_time_s").get<double>() == Approx(wall));
  CHECK(wall >= stages.at("time_s").get<double>() + stages.at("initial_guess_time_s").get<double>());
  CHECK(text.out.find("time by stage: noise_scale ") != std::string::npos);
  // The time's breakdown: parts of time_s (robust solve and refinement).
  double parts = 0.0;
  for (const char* key : {"preprocessor_time_s", "linear_solver_time_s", "jacobian_time_s",
                          "residual_time_s"}) {
    CHECK(j.at(key).get<double>() >= 0.0);
    parts += j.at(key).get<double>();
  }
  CHECK(parts <= j.at("time_s").get<double>());
  CHECK(j.at("linear_solver_time_s").get<double>() > 0.0);
  CHECK(j.at("initial_guess_time_s").get<double>() > 0.0);
  // The narrowed gate's keys; a simulated graph's information is its noise's,
  // so nothing narrows.
  for (const char* key : {"inlier_noise_scale", "inlier_noise_upper_scale", "inlier_noise_cycles",
                          "narrow_newly_rejected", "narrow_iterations", "narrow_time_s"}) {
    CHECK(j.contains(key));
  }
  CHECK(j.at("narrowed") == false);
  CHECK(j.at("narrow_factor") == 1.0);
  // Readmission's keys: its time is part of time_s; every closure says
  // whether it was readmitted, and the count agrees.
  CHECK(j.at("readmit_time_s").get<double>() >= j.at("readmit_test_time_s").get<double>());
  CHECK(j.at("readmit_time_s").get<double>() <= j.at("time_s").get<double>());
  const auto info = nlohmann::json::parse(Run({"info", out, "--json"}).out);
  // One switch per loop closure, written with the graph.
  CHECK(info.at("switches") == info.at("loop_closures"));
  CHECK(info.at("switchable_edges") == info.at("loop_closures"));
  std::ifstream report_file(report);
  const auto full = nlohmann::json::parse(report_file);
  CHECK(full.at("closures").size() == j.at("accepted").get<std::size_t>() + j.at("rejected").get<std::size_t>());
  std::size_t readmitted = 0;
  for (const auto& c : full.at("closures")) readmitted += c.at("readmitted").get<bool>() ? 1 : 0;
  CHECK(readmitted == j.at("readmitted").get<std::size_t>());
  // Whether the robust solve ended when its decisions settled; never with
  // --no-settled-stop, and the decisions are the same.
  CHECK(j.at("settled").is_boolean());
  const Result full_solve = Run({"optimize", graph, "-o", out, "--json", "--no-settled-stop"});
  REQUIRE(full_solve.status == 0);
  const auto unsettled = nlohmann::json::parse(full_solve.out);
  CHECK(unsettled.at("settled") == false);
  CHECK(unsettled.at("accepted") == j.at("accepted"));
  // --drop-rejected writes a graph without switches.
  REQUIRE(Run({"optimize", graph, "-o", out, "--drop-rejected"}).status == 0);
  CHECK(nlohmann::json::parse(Run({"info", out, "--json"}).out).at("switches") == 0);
  std::filesystem::remove_all(dir);
}

TEST_CASE("inject, optimize, evaluate: the experiment in three commands", "[apps][inject][evaluate]") {
  const auto dir = testing::TempDir("cli_experiment");
  const std::string graph = (dir / "graph.g2o").string(), truth = (dir / "truth.g2o").string();
  REQUIRE(Run({"generate-graph", "-o", graph, "--truth", truth, "--poses", "300", "--seed", "2"})
              .status == 0);
  const std::string spoiled = (dir / "spoiled.g2o").string(), labels = (dir / "labels.csv").string();
  const Result inject = Run({"inject", graph, "-o", spoiled, "--outliers", "30", "--policy",
                             "local-grouped", "--group-size", "3", "--seed", "4", "--labels", labels});
  REQUIRE(inject.status == 0);
  CHECK(inject.out.find("injected 30 false loop closures (local-grouped, 10 groups, seed 4)") !=
        std::string::npos);
  // Same seed, same bytes.
  const std::string again = (dir / "again.g2o").string();
  REQUIRE(Run({"inject", graph, "-o", again, "--outliers", "30", "--policy", "local-grouped",
               "--group-size", "3", "--seed", "4"}).status == 0);
  CHECK(testing::ReadText(spoiled) == testing::ReadText(again));

  const std::string corrected = (dir / "corrected.g2o").string();
  REQUIRE(Run({"optimize", spoiled, "-o", corrected}).status == 0);
  const Result evaluate = Run({"evaluate", corrected, "--truth", truth, "--labels", labels, "--json"});
  REQUIRE(evaluate.status == 0);
  const auto j = nlohmann::json::parse(evaluate.out);
  CHECK(j.at("poses") == 300);
  CHECK(j.at("precision") == 1.0);
  CHECK(j.at("recall").get<double>() > 0.99);
  CHECK(j.at("false_positives") == 0);
  CHECK(j.at("true_negatives") == 30);
  CHECK(j.at("outlier_rejection") == 1.0);
  CHECK(j.at("outliers_explained_by_truth") == 0);
  CHECK(j.at("unexplained_outlier_rejection") == 1.0);
  // The simulated noise is small: the corrected map is within centimetres.
  CHECK(j.at("ate_rmse").get<double>() < 0.2);
  CHECK(j.at("rmse_anchored").get<double>() >= j.at("ate_rmse").get<double>());

  // Plain least squares keeps the false closures: precision drops, ATE grows.
  const std::string plain = (dir / "plain.g2o").string(), report = (dir / "plain.json").string();
  REQUIRE(Run({"optimize", spoiled, "-o", plain, "--method", "none", "--report", report}).status == 0);
  const auto k = nlohmann::json::parse(
      Run({"evaluate", plain, "--truth", truth, "--labels", labels, "--report", report, "--json"}).out);
  CHECK(k.at("false_positives") == 30);
  CHECK(k.at("outlier_rejection") == 0.0);
  CHECK(k.at("ate_rmse").get<double>() > j.at("ate_rmse").get<double>());
  std::filesystem::remove_all(dir);
}

// Every method's decisions travel with the corrected graph: export and
// evaluate, given nothing else, count the closures optimize rejected.
TEST_CASE("export and evaluate read each method's decisions from the corrected graph", "[apps][evaluate][export]") {
  const auto dir = testing::TempDir("cli_decisions");
  const std::string graph = (dir / "g.g2o").string(), truth = (dir / "t.g2o").string();
  const std::string spoiled = (dir / "s.g2o").string(), labels = (dir / "l.csv").string();
  REQUIRE(Run({"generate-graph", "-o", graph, "--truth", truth, "--poses", "400"}).status == 0);
  REQUIRE(Run({"inject", graph, "-o", spoiled, "--outliers", "100", "--labels", labels}).status == 0);
  for (const char* method : {"dcs", "cauchy", "huber", "gnc", "switchable"}) {
    CAPTURE(method);
    const std::string out = (dir / (std::string(method) + ".g2o")).string();
    const std::string report = (dir / (std::string(method) + ".json")).string();
    REQUIRE(Run({"optimize", spoiled, "-o", out, "--method", method, "--report", report}).status == 0);
    const auto r = nlohmann::json::parse(testing::ReadText(report));
    std::set<std::pair<int, int>> rejected;
    for (const auto& c : r.at("closures")) {
      if (!c.at("accepted").get<bool>()) rejected.emplace(c.at("from").get<int>(), c.at("to").get<int>());
    }
    CHECK(rejected.size() == r.at("rejected").get<std::size_t>());
    REQUIRE(Run({"export", out, "-o", (dir / "e.json").string()}).status == 0);
    const auto exported = nlohmann::json::parse(testing::ReadText(dir / "e.json"));
    std::set<std::pair<int, int>> exported_rejected;
    for (const auto& c : exported.at("constraints")) {
      if (!c.at("accepted").get<bool>()) exported_rejected.emplace(c.at("from").get<int>(), c.at("to").get<int>());
    }
    CHECK(exported_rejected == rejected);
    const Result plain = Run({"evaluate", out, "--truth", truth, "--labels", labels, "--json"});
    const Result with_report = Run({"evaluate", out, "--truth", truth, "--labels", labels, "--report", report, "--json"});
    REQUIRE(plain.status == 0);
    REQUIRE(with_report.status == 0);
    const auto a = nlohmann::json::parse(plain.out), b = nlohmann::json::parse(with_report.out);
    for (const char* key : {"precision", "recall", "true_positives", "false_positives"}) CHECK(a.at(key) == b.at(key));
    CHECK(a.at("true_positives").get<std::size_t>() + a.at("false_positives").get<std::size_t>() ==
          r.at("accepted").get<std::size_t>());
  }
  std::filesystem::remove_all(dir);
}

TEST_CASE("inject --groups N --group-size G adds N x G edges, as Vertigo's generator does", "[apps][inject]") {
  const auto dir = testing::TempDir("cli_groups");
  const std::string graph = (dir / "g.g2o").string();
  REQUIRE(Run({"generate-graph", "-o", graph, "--poses", "200"}).status == 0);
  const Result groups = Run({"inject", graph, "-o", (dir / "a.g2o").string(), "--groups", "4", "--group-size", "3",
                             "--policy", "random-grouped", "--labels", (dir / "a.csv").string()});
  REQUIRE(groups.status == 0);
  CHECK(groups.out.starts_with("injected 12 false loop closures (random-grouped, 4 groups"));
  std::map<int, int> per_group;
  for (const ClosureLabel& l : ReadClosureLabelsFile(dir / "a.csv")) {
    if (l.outlier) ++per_group[*l.group];
  }
  CHECK(per_group == std::map<int, int>{{0, 3}, {1, 3}, {2, 3}, {3, 3}});
  // The same edges as --outliers 12 with groups of 3.
  REQUIRE(Run({"inject", graph, "-o", (dir / "b.g2o").string(), "--outliers", "12", "--group-size", "3", "--policy",
               "random-grouped"}).status == 0);
  CHECK(testing::ReadText(dir / "a.g2o") == testing::ReadText(dir / "b.g2o"));
  CHECK(Run({"inject", graph, "-o", (dir / "c.g2o").string(), "--groups", "4", "--outliers", "12"}).status == 2);
  CHECK(Run({"inject", graph, "-o", (dir / "c.g2o").string()}).status == 2);
  CHECK(Run({"inject", graph, "-o", (dir / "c.g2o").string(), "--groups", "100000", "--group-size", "10", "--policy",
             "random-grouped"}).status == 1);
  std::filesystem::remove_all(dir);
}

TEST_CASE("inject writes switchable files and hierarchical parents", "[apps][inject]") {
  const auto dir = testing::TempDir("cli_inject");
  const std::string graph = (dir / "graph.g2o").string(), out = (dir / "out.g2o").string();
  REQUIRE(Run({"generate-graph", "-o", graph, "--poses", "100"}).status == 0);
  REQUIRE(Run({"inject", graph, "-o", out, "--outliers", "6", "--policy", "hierarchical",
               "--group-size", "3", "--switchable", "--information", "2"}).status == 0);
  const std::string text = testing::ReadText(out);
  CHECK(text.find("VERTEX_SWITCH") != std::string::npos);
  CHECK(text.find("EDGE_SE2_SWITCHABLE") != std::string::npos);
  CHECK(text.find(" visual\n") != std::string::npos);
  CHECK(text.find(" inferred ") != std::string::npos);  // "#CATGRAPH_CLOSURE id inferred parent"
  const Result bad = Run({"inject", graph, "-o", out, "--outliers", "6", "--information", "1", "2"});
  CHECK(bad.status == 1);
  CHECK(bad.err.find("--information: expected 1 value") != std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST_CASE("a switchable file inject writes is solved as well as the plain one; Vertigo's prior of 1 is not",
          "[apps][inject]") {
  const auto dir = testing::TempDir("cli_inject_switchable");
  const std::string graph = (dir / "graph.g2o").string();
  REQUIRE(Run({"generate-graph", "-o", graph, "--poses", "300", "--seed", "2"}).status == 0);
  // Accepted closures after `optimize`, for each way of writing the same
  // 30 false closures.
  auto accepted = [&](const std::string& name, std::vector<std::string> extra) {
    const std::string spoiled = (dir / (name + ".g2o")).string(), solved = (dir / (name + "-o.g2o")).string();
    std::vector<std::string> inject = {"inject", graph, "-o", spoiled, "--outliers", "30", "--seed", "4"};
    inject.insert(inject.end(), extra.begin(), extra.end());
    REQUIRE(Run(inject).status == 0);
    const Result r = Run({"optimize", spoiled, "-o", solved, "--json"});
    REQUIRE(r.status == 0);
    return nlohmann::json::parse(r.out).at("accepted").get<int>();
  };
  const int plain = accepted("plain", {});
  CHECK(accepted("switchable", {"--switchable"}) == plain);
  CHECK(testing::ReadText(dir / "switchable.g2o").find("EDGE_SWITCH_PRIOR 300 1 16.26") != std::string::npos);
  // Vertigo's prior switches off true closures beyond one sigma.
  CHECK(accepted("vertigo", {"--switchable", "--switch-prior-information", "1"}) < plain / 2);
  std::filesystem::remove_all(dir);
}

TEST_CASE("export writes TUM, JSON, DOT, SVG and PNG, edges-only graphs are refused by name",
          "[apps][export]") {
  const auto dir = testing::TempDir("cli_export");
  const std::string graph = (dir / "graph.g2o").string();
  REQUIRE(Run({"generate-graph", "-o", graph, "--poses", "50"}).status == 0);
  for (const char* ext : {"tum", "json", "dot", "svg", "png"}) {
    const std::string out = (dir / (std::string("out.") + ext)).string();
    const Result r = Run({"export", graph, "-o", out});
    CAPTURE(ext, r.err);
    CHECK(r.status == 0);
    CHECK(std::filesystem::file_size(out) > 100);
  }
  CHECK(Run({"export", graph, "--format", "tum", "-o", (dir / "traj.txt").string()}).status == 0);
  const Result unknown = Run({"export", graph, "-o", (dir / "out.xyz").string()});
  CHECK(unknown.status == 1);
  CHECK(unknown.err.find("give --format") != std::string::npos);
  const Result edges_only =
      Run({"export", testing::Fixture("edges_only.g2o").string(), "-o", (dir / "e.tum").string()});
  CHECK(edges_only.status == 1);
  CHECK(edges_only.err.find("edges_only.g2o: pose") != std::string::npos);
  CHECK(!std::filesystem::exists(dir / "e.tum"));
  std::filesystem::remove_all(dir);
}

TEST_CASE("a mistyped command or option gets a suggestion; output formats are told case-insensitively",
          "[apps][bad-input]") {
  const Result command = Run({"optimze", "g.g2o"});
  CHECK(command.status == 2);
  CHECK(command.err.starts_with("catgraph: unknown command 'optimze' (did you mean 'optimize'?)\n"));
  const Result option = Run({"localize", "d", "-o", "x", "--particels", "30"});
  CHECK(option.status == 2);
  CHECK(option.err.find("--particels (did you mean '--particles'?)") != std::string::npos);
  const Result unlike = Run({"frobnicate"});
  CHECK(unlike.err.starts_with("catgraph: unknown command 'frobnicate'\n"));  // nothing near: no guess

  const auto dir = testing::TempDir("cli_case");
  const std::string graph = (dir / "g.g2o").string();
  REQUIRE(Run({"generate-graph", "-o", graph, "--poses", "50"}).status == 0);
  for (const char* name : {"a.PNG", "b.Svg", "c.TUM", "d.Json"}) {
    const Result r = Run({"export", graph, "-o", (dir / name).string()});
    CAPTURE(name, r.err);
    CHECK(r.status == 0);
    CHECK(std::filesystem::file_size(dir / name) > 100);
  }
  CHECK(testing::ReadText(dir / "a.PNG").starts_with("\x89PNG"));
  std::filesystem::remove_all(dir);
}

TEST_CASE("evaluate names the file at fault", "[apps][evaluate][bad-input]") {
  const auto dir = testing::TempDir("cli_evaluate");
  const std::string graph = (dir / "graph.g2o").string();
  REQUIRE(Run({"generate-graph", "-o", graph, "--poses", "50"}).status == 0);
  std::ofstream(dir / "short.txt") << "0 0 0\n1 0 0\n";
  const Result r = Run({"evaluate", graph, "--truth", (dir / "short.txt").string()});
  CHECK(r.status == 1);
  CHECK(r.err.find("short.txt: pose 2 of the estimate has no ground truth") != std::string::npos);
  const Result missing = Run({"evaluate", graph, "--truth", (dir / "nope.txt").string()});
  CHECK(missing.status == 1);
  CHECK(missing.err.find("nope.txt: no such file") != std::string::npos);

  // Labels that do not belong to the estimate are errors naming the line,
  // never a precision over the wrong closures.
  const std::string truth = (dir / "truth.g2o").string(), spoiled = (dir / "spoiled.g2o").string();
  const std::string labels = (dir / "labels.csv").string();
  REQUIRE(Run({"generate-graph", "-o", graph, "--truth", truth, "--poses", "200"}).status == 0);
  REQUIRE(Run({"inject", graph, "-o", spoiled, "--outliers", "5", "--labels", labels}).status == 0);
  const std::string good = testing::ReadText(labels);
  REQUIRE(Run({"evaluate", spoiled, "--truth", truth, "--labels", labels}).status == 0);
  const std::string header = good.substr(0, good.find('\n') + 1);
  const std::string first_row = good.substr(header.size(), good.find('\n', header.size()) + 1 - header.size());
  const std::vector<std::pair<std::string, std::string>> bad = {
      {header, "labels.csv: holds the header alone"},
      {header + good.substr(header.size() + first_row.size()), "labels.csv: has no label for the estimate's closure"},
      {good + "999999," + first_row.substr(first_row.find(',') + 1), "is labelled more often than the estimate has it"},
      {good + "999999,4294967295,3,1,injected,,\n", "pose 4294967295 is not in the estimate"},
  };
  for (const auto& [text, message] : bad) {
    std::ofstream(labels) << text;
    const Result e = Run({"evaluate", spoiled, "--truth", truth, "--labels", labels});
    CAPTURE(message, e.err);
    CHECK(e.status == 1);
    CHECK(e.err.find(message) != std::string::npos);
  }
  std::filesystem::remove_all(dir);
}

TEST_CASE("localize refuses a motion noise that is not three positive numbers, by name", "[apps][localize][bad-input]") {
  // Parsing fails before the dataset is read: no dataset is needed.
  for (const std::string option : {"--motion-sigma", "--new-place-motion-sigma", "--odometric-motion-sigma"}) {
    for (const std::vector<std::string>& sigma :
         {std::vector<std::string>{"0.02", "nan", "0.02"}, {"0.02", "-0.05", "0.02"}, {"0.02", "0.05"}}) {
      std::vector<std::string> args = {"localize", "no-such-dataset", "-o", "unused", option};
      args.insert(args.end(), sigma.begin(), sigma.end());
      const Result r = Run(args);
      CAPTURE(option, r.err);
      CHECK(r.status != 0);
      CHECK(r.err.find(option) != std::string::npos);
    }
  }
}

TEST_CASE("localize refuses a stay fraction, a stay relative offset, an observation window, a closure evidence "
          "fraction, a retry count, an observation model or a new-place offset out of range, by name",
          "[apps][localize][bad-input]") {
  const std::vector<std::pair<std::string, std::vector<std::string>>> bad = {
      {"--new-place-stay-fraction", {"1.5", "-0.1", "nan", "half"}},
      {"--new-place-stay-relative-offset", {"1", "-0.1", "nan", "half"}},
      {"--observation-window", {"-0.1", "nan", "inf", "wide"}},
      {"--closure-min-evidence", {"1.5", "-0.1", "nan", "a fifth"}},
      {"--total-path-retries", {"-1", "101", "1.5", "two"}},
      {"--observation", {"seqslam", "FABMAP", ""}},
      {"--new-place-offset", {"nan", "inf", "many"}},
  };
  for (const auto& [option, values] : bad) {
    for (const std::string& value : values) {
      const Result r = Run({"localize", "no-such-dataset", "-o", "unused", option, value});
      CAPTURE(option, value, r.err);
      CHECK(r.status != 0);
      CHECK(r.err.find(option) != std::string::npos);
    }
  }
  // In range, the options parse and the dataset is looked for.
  const Result ok = Run({"localize", "no-such-dataset", "-o", "unused", "--new-place-stay-fraction", "1",
                         "--new-place-stay-relative-offset", "0.99", "--observation-window", "0.4",
                         "--closure-min-evidence", "1", "--no-heading-likelihood", "--hold-after-closure",
                         "--total-path-retries", "100", "--observation", "holistic", "--new-place-offset", "-3"});
  CHECK(ok.status != 0);
  CHECK(ok.err.find("no-such-dataset") != std::string::npos);
}

TEST_CASE("localize and map list at most 15 options in --help; an options file's mistakes name its line",
          "[apps][localize][map][options]") {
  for (const char* command : {"localize", "map"}) {
    const Result help = Run({command, "--help"});
    REQUIRE(help.status == 0);
    std::istringstream lines(help.out);
    int options = 0;
    for (std::string line; std::getline(lines, line);) options += line.starts_with("  -");
    CAPTURE(command, help.out);
    CHECK(options >= 10);
    CHECK(options <= 15);
    CHECK(help.out.find("--options") != std::string::npos);
    CHECK(help.out.find("--gate-base") == std::string::npos);  // accepted, listed in docs/cli.md
  }
  // A command's own options stay listed beside the filter's.
  for (const char* command : {"localize", "map", "hierarchy-experiment", "inference-sweep"}) {
    const Result help = Run({command, "--help"});
    CAPTURE(command, help.out);
    CHECK(help.out.find("-o,--output") != std::string::npos);
  }
  const auto dir = testing::TempDir("cli_options");
  std::ofstream(dir / "bad.yaml") << "front_end:\n  filter:\n    gate:\n      fraction: -0.5\n";
  const Result bad = Run({"map", "no-such-dataset", "-o", (dir / "out").string(), "--options",
                          (dir / "bad.yaml").string()});
  CHECK(bad.status == 1);
  CHECK(bad.err.find("bad.yaml:4: CatGraphOptions: gate.") != std::string::npos);
  const Result preset = Run({"localize", "no-such-dataset", "-o", (dir / "out").string(), "--preset", "spec"});
  CHECK(preset.status == 2);
  CHECK(preset.err.find("--preset") != std::string::npos);
  CHECK_FALSE(std::filesystem::exists(dir / "out"));
  std::filesystem::remove_all(dir);
}

// Sizes from flags have documented maxima, checked before anything is
// allocated: the flag is named, nothing aborts.
TEST_CASE("sizes beyond their documented maximum are refused by flag name", "[apps][bad-input][bounds]") {
  const std::vector<std::pair<std::vector<std::string>, std::string>> bad = {
      {{"inject", "g.g2o", "-o", "x.g2o", "--outliers", "2147483647"}, "--outliers"},
      {{"inject", "g.g2o", "-o", "x.g2o", "--outliers", "-1"}, "--outliers"},
      {{"inject", "g.g2o", "-o", "x.g2o", "--outliers", "10", "--group-size", "1000000"}, "--group-size"},
      {{"generate-graph", "-o", "x.g2o", "--poses", "2000000", "--grid-cells", "5000"}, "--poses"},
      {{"generate-graph", "-o", "x.g2o", "--poses", "100000"}, "--grid-cells"},
      {{"simulate", "--scenario", "office-change", "-o", "x", "--threads", "2000"}, "--threads"},
      {{"localize", "d", "-o", "x", "--threads", "2000"}, "--threads"},
      {{"map", "d", "-o", "x", "--threads", "-1"}, "--threads"},
      {{"sweep", "--config", "s.yaml", "--jobs", "100000"}, "--jobs"},
  };
  for (const auto& [args, flag] : bad) {
    const Result r = Run(args);
    CAPTURE(args, r.err);
    CHECK(r.status == 2);
    CHECK(r.err.find(flag) != std::string::npos);
    CHECK(r.err.find("::") == std::string::npos);  // no C++ name
  }
}

TEST_CASE("localize holds after a closure by default; --no-hold-after-closure turns it off, --hold-after-closure "
          "keeps it",
          "[apps][localize]") {
  const auto parse = [](std::vector<std::string> args) {
    CLI::App app;
    LocalizeCommandOptions o;
    AddLocalizationOptions(app, o);
    std::vector<std::string> reversed(args.rbegin(), args.rend());  // CLI11 parses a reversed vector
    app.parse(reversed);
    return o.pipeline.front_end.filter.new_place.hold_after_closure;
  };
  CHECK(parse({}));
  CHECK(parse({"--hold-after-closure"}));
  CHECK_FALSE(parse({"--no-hold-after-closure"}));
  CHECK(CatGraphOptions{}.new_place.hold_after_closure);
}

TEST_CASE("sweep runs a configuration, resumes, merges shards and plots", "[apps][sweep]") {
  const auto dir = testing::TempDir("cli_sweep");
  REQUIRE(Run({"generate-graph", "-o", (dir / "g.g2o").string(), "--truth",
               (dir / "t.g2o").string(), "--poses", "80"}).status == 0);
  std::ofstream(dir / "sweep.yaml")
      << "datasets:\n  - {name: sim, graph: g.g2o, truth: t.g2o}\nmethods: [none, dcs]\n"
         "policies: [random]\noutliers: [0, 4]\nseeds: 2\n";
  const std::string config = (dir / "sweep.yaml").string();
  const Result first = Run({"sweep", "--config", config, "-o", (dir / "all.csv").string(),
                            "--quiet", "--plot", (dir / "fig").string()});
  REQUIRE(first.status == 0);
  CHECK(first.out.find("8 runs, 0 already in") != std::string::npos);
  CHECK(std::filesystem::exists(dir / "fig-sim.svg"));
  const Result second = Run({"sweep", "--config", config, "-o", (dir / "all.csv").string(), "--quiet"});
  CHECK(second.out.find("8 already in") != std::string::npos);
  for (const char* shard : {"0/2", "1/2"}) {
    REQUIRE(Run({"sweep", "--config", config, "--shard", shard, "--quiet", "-o",
                 (dir / (std::string("s") + shard[0] + ".csv")).string()}).status == 0);
  }
  REQUIRE(Run({"sweep", "merge", (dir / "s0.csv").string(), (dir / "s1.csv").string(), "-o",
               (dir / "merged.csv").string()}).status == 0);
  CHECK(ReadSweepCsv(dir / "merged.csv").size() == 8);
  const Result no_config = Run({"sweep"});
  CHECK(no_config.status == 2);
  std::filesystem::remove_all(dir);
}

// `import` as a user runs it: a simulated recording's images with a times
// file and its ground truth as the pose CSV; the layout in any case.
TEST_CASE("import reads an image folder with its times and poses, and names a layout it does not know",
          "[apps][import]") {
  const auto dir = testing::TempDir("cli_import");
  const std::string data = (dir / "data").string();
  REQUIRE(Run({"simulate", "--scenario", "office-static", "-o", data, "--frames", "30", "--quiet"}).status == 0);
  const Dataset source = ReadDataset(data);
  {
    std::ofstream times(dir / "times.txt");
    times.precision(17);
    for (const auto& f : source.frames) times << f.timestamp_s << "\n";
  }
  const Result run = Run({"import", "Folder", (dir / "data" / "images").string(), "--times",
                          (dir / "times.txt").string(), "--poses", (dir / "data" / "groundtruth.csv").string(),
                          "-o", (dir / "imported").string(), "--quiet"});
  INFO(run.out << run.err);
  REQUIRE(run.status == 0);
  CHECK(run.out == "wrote " + (dir / "imported").string() +
                       ": 30 frames in 1 traversal; odometry made from the poses (meta.json), ground truth "
                       "from the poses\n");
  const Dataset imported = ReadDataset(dir / "imported");
  REQUIRE(imported.frames.size() == 30);
  CHECK(imported.meta.synthetic_odometry);
  for (std::size_t k = 0; k < 30; ++k) {
    CHECK(imported.frames[k].timestamp_s == Approx(source.frames[k].timestamp_s).margin(1e-6));
    const Pose2 a = InterpolatePose(imported.ground_truth, imported.frames[k].timestamp_s);
    const Pose2 b = InterpolatePose(source.ground_truth, source.frames[k].timestamp_s);
    CHECK((a.translation() - b.translation()).norm() < 1e-5);
    CHECK(testing::ReadText(imported.ImagePath(k)) == testing::ReadText(source.ImagePath(k)));
  }
  const Result unknown = Run({"import", "rosbag2", data, "-o", (dir / "x").string()});
  CHECK(unknown.status == 2);
  CHECK_THAT(unknown.err, Catch::Contains("rosbag2") && Catch::Contains("folder"));
  const Result no_poses = Run({"import", "folder", (dir / "data" / "images").string(), "-o", (dir / "y").string()});
  CHECK(no_poses.status == 1);
  CHECK_THAT(no_poses.err, Catch::Contains("needs an odometry CSV, a pose CSV or both"));
  CHECK_FALSE(std::filesystem::exists(dir / "y"));
  std::filesystem::remove_all(dir);
}

// Every command that writes refuses, before any work, to write over one of
// its inputs or into a folder of the user's; the inputs stay byte for byte.
TEST_CASE("no command writes over its input or into a folder catgraph did not write", "[apps][output]") {
  const auto dir = testing::TempDir("cli_outputs");
  const std::string g = (dir / "g.g2o").string(), t = (dir / "t.g2o").string();
  REQUIRE(Run({"generate-graph", "-o", g, "--truth", t, "--poses", "60"}).status == 0);
  const std::string data = (dir / "data").string();
  REQUIRE(Run({"simulate", "--scenario", "office-change", "-o", data, "--frames", "8", "--quiet"}).status == 0);
  std::ofstream(dir / "notes.csv") << "my,own\n1,2\n3,4";  // not a sweep's, no final newline
  std::filesystem::create_directories(dir / "user" / "images");
  std::ofstream(dir / "user" / "images" / "000000.png") << "mine";

  auto snapshot = [&] {
    std::map<std::string, std::string> files;
    for (const auto& e : std::filesystem::recursive_directory_iterator(dir)) {
      if (e.is_regular_file()) files[e.path().string()] = testing::ReadText(e.path());
    }
    return files;
  };
  const auto before = snapshot();
  const std::string sweep = (dir / "sweep.yaml").string();
  std::ofstream(sweep) << "datasets:\n  - {name: sim, graph: g.g2o}\nmethods: [none]\npolicies: [random]\n"
                          "outliers: [0]\nseeds: 1\n";
  const std::vector<std::vector<std::string>> refused = {
      {"simulate", "--scenario", "office-change", "-o", (dir / "user").string(), "--frames", "2", "--quiet"},
      {"optimize", g, "-o", g},
      {"optimize", g, "-o", (dir / "o.g2o").string(), "--report", g},
      {"inject", g, "-o", (dir / "i.g2o").string(), "--outliers", "5", "--labels", g},
      {"inject", g, "-o", (dir / "." / "g.g2o").string(), "--outliers", "5"},
      {"generate-graph", "-o", (dir / "x.g2o").string(), "--truth", (dir / "x.g2o").string()},
      {"export", g, "-o", g},
      {"vocabulary", "train", data, "-o", data + "/frames.csv"},
      {"plot-dataset", data, "-o", data + "/images/000000.png"},
      {"localize", data, "-o", data, "--quiet"},
      {"map", data, "-o", dir.string(), "--quiet"},
      {"sad-match", data, "-o", data},
      {"sweep", "--config", sweep, "-o", g},
      {"sweep", "--config", sweep, "-o", (dir / "notes.csv").string(), "--quiet"},
      {"sweep", "merge", (dir / "notes.csv").string(), "-o", (dir / "notes.csv").string()},
  };
  for (const auto& args : refused) {
    std::string line;
    for (const auto& a : args) line += a + " ";
    INFO(line);
    const Result r = Run(args);
    CHECK(r.status == 1);
    CHECK(r.err.find("catgraph: error: ") == 0);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  }
  std::remove((dir / "sweep.yaml").c_str());
  CHECK(snapshot() == before);

  // Two sweeps on one CSV: the second is refused while the first holds it.
  std::ofstream(sweep) << "datasets:\n  - {name: sim, graph: g.g2o}\nmethods: [none]\npolicies: [random]\n"
                          "outliers: [0]\nseeds: 1\n";
  const std::string csv = (dir / "runs.csv").string();
  const int fd = ::open(csv.c_str(), O_WRONLY | O_CREAT, 0644);
  REQUIRE(::flock(fd, LOCK_EX) == 0);
  const Result locked = Run({"sweep", "--config", sweep, "-o", csv, "--quiet"});
  CHECK(locked.status == 1);
  CHECK(locked.err.find("another sweep is writing this CSV") != std::string::npos);
  ::close(fd);
  CHECK(Run({"sweep", "--config", sweep, "-o", csv, "--quiet"}).status == 0);
  CHECK(ReadSweepCsv(csv).size() == 1);
  std::filesystem::remove_all(dir);
}

TEST_CASE("simulate lists and prints its scenarios and writes a dataset that plot-dataset draws",
          "[apps][simulate]") {
  const Result list = Run({"simulate", "--list"});
  REQUIRE(list.status == 0);
  CHECK(list.out == "office-static\noffice-change\noffice-split\noffice-lighting\noffice-training\n");
  const Result print = Run({"simulate", "--print-scenario", "office-change"});
  REQUIRE(print.status == 0);
  CHECK(print.out.find("name: office-change") != std::string::npos);

  const auto dir = testing::TempDir("cli_simulate");
  const Result sim = Run({"simulate", "--scenario", "office-change", "-o", (dir / "data").string(),
                          "--frames", "20", "--seed", "3", "--quiet"});
  REQUIRE(sim.status == 0);
  CHECK(sim.out.find("scenario office-change, seed 3, 20 frames") != std::string::npos);
  CHECK(std::filesystem::file_size(dir / "data" / "images" / "000019.png") > 10000);
  const Result plot = Run({"plot-dataset", (dir / "data").string(), "-o", (dir / "plan.png").string(),
                           "--pair-at", "4,1.2", "--pair-output", (dir / "pair.png").string()});
  REQUIRE(plot.status == 0);
  // The plan is drawn: lines over a good part of the picture, and the
  // changed region's band in the figures' change colour (translucent over
  // white).
  const cv::Mat3b plan = cv::imread((dir / "plan.png").string(), cv::IMREAD_COLOR);
  REQUIRE(!plan.empty());
  int drawn = 0, change_band = 0;
  const auto mixed = [](double c) { return 255.0 - 0.4 * (255.0 - 255.0 * c); };
  const cv::Vec3d band(mixed(plot::kChangedRegionColor.b), mixed(plot::kChangedRegionColor.g),
                       mixed(plot::kChangedRegionColor.r));
  for (const cv::Vec3b& p : cv::Mat_<cv::Vec3b>(plan)) {
    drawn += std::min({p[0], p[1], p[2]}) < 200 ? 1 : 0;
    change_band += cv::norm(cv::Vec3d(p[0], p[1], p[2]) - band, cv::NORM_INF) < 12.0 ? 1 : 0;
  }
  CHECK(drawn > static_cast<int>(plan.total() / 50));
  CHECK(change_band > 1000);
  CHECK(std::filesystem::file_size(dir / "pair.png") > 20000);
  // A scenario file of the user's, with a mistake, is named with its line.
  std::ofstream(dir / "mine.yaml") << print.out << "extra_key: 1\n";
  const Result bad = Run({"simulate", "--scenario", (dir / "mine.yaml").string(), "-o", (dir / "x").string()});
  CHECK(bad.status == 1);
  CHECK(bad.err.find("mine.yaml:") != std::string::npos);
  CHECK(bad.err.find("unknown key 'extra_key'") != std::string::npos);
  std::filesystem::remove_all(dir);
}

// A TUM file as evo reads it: '#' lines skipped, 8 numbers per line
// (timestamp tx ty tz qx qy qz qw).
std::vector<std::array<double, 8>> ReadTumAsEvo(const std::filesystem::path& path) {
  std::vector<std::array<double, 8>> rows;
  std::istringstream in(testing::ReadText(path));
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::array<double, 8> row{};
    for (double& v : row) REQUIRE(static_cast<bool>(fields >> v));
    std::string rest;
    CHECK_FALSE(static_cast<bool>(fields >> rest));
    rows.push_back(row);
  }
  return rows;
}

// RMSE of the positions after the best rotation and translation of the
// first onto the second (closed form in 2D; Umeyama without scale).
double RigidAlignedRmse(const std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>>& pairs) {
  Eigen::Vector2d mean_a = Eigen::Vector2d::Zero(), mean_b = Eigen::Vector2d::Zero();
  for (const auto& [a, b] : pairs) mean_a += a, mean_b += b;
  mean_a /= static_cast<double>(pairs.size());
  mean_b /= static_cast<double>(pairs.size());
  double cross = 0.0, dot = 0.0;
  for (const auto& [a, b] : pairs) {
    const Eigen::Vector2d p = a - mean_a, q = b - mean_b;
    cross += p.x() * q.y() - p.y() * q.x();
    dot += p.dot(q);
  }
  const Eigen::Rotation2Dd rotation(std::atan2(cross, dot));
  double sum = 0.0;
  for (const auto& [a, b] : pairs) sum += (rotation * (a - mean_a) + mean_b - b).squaredNorm();
  return std::sqrt(sum / static_cast<double>(pairs.size()));
}

// A picture worth looking at: decodes, is large, and is not one flat colour.
void CheckNonTrivialImage(const std::filesystem::path& path) {
  INFO(path);
  const cv::Mat image = cv::imread(path.string(), cv::IMREAD_GRAYSCALE);
  REQUIRE_FALSE(image.empty());
  CHECK(image.cols >= 800);
  CHECK(image.rows >= 500);
  cv::Scalar mean, stddev;
  cv::meanStdDev(image, mean, stddev);
  CHECK(stddev[0] > 10.0);
}

// A CSV the commands write: its header line and its rows split at commas
// (none of their fields holds one; an empty last field is kept).
struct Csv {
  std::string header;
  std::vector<std::vector<std::string>> rows;
};

Csv ReadCsv(const std::filesystem::path& path) {
  std::ifstream in(path);
  Csv csv;
  REQUIRE(std::getline(in, csv.header));
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> fields;
    std::stringstream ss(line);
    for (std::string x; std::getline(ss, x, ',');) fields.push_back(x);
    if (!line.empty() && line.back() == ',') fields.emplace_back();
    csv.rows.push_back(std::move(fields));
  }
  return csv;
}

// A built-in scenario simulated into root / "data", and the front end's
// inputs for it (the default vocabulary, trained on its traversal 1).
struct PreparedScenario {
  Dataset dataset;
  FrontEndInputs inputs;
};

PreparedScenario SimulateAndPrepare(const std::string& scenario, const std::filesystem::path& root,
                                    LocalizeCommandOptions& o) {
  const Result sim = Run({"simulate", "--scenario", scenario, "-o", (root / "data").string(), "--quiet"});
  INFO(sim.out << sim.err);
  REQUIRE(sim.status == 0);
  Dataset d = ReadDataset(root / "data");
  o.quiet = true;
  std::ostringstream log;
  FrontEndInputs in = PrepareFrontEnd(d, o, log);
  return {std::move(d), std::move(in)};
}

// office-static's acceptance with the defaults (nothing changes
// between the traversals), and #7's: the paper's claim, "identical in a
// static environment". The robot held on the map through weak frames, and
// only once it has closed (docs/frontend.md "Held after a closure"),
// CAT-Graph closes traversal 2 all but in full (99.5 %), none wrong, and
// CAT-Graph+ adds nothing: the same visual closures, the same best
// hypothesis every frame, no inference made or discarded. Measured for
// filter seeds 1-5; the earlier defaults (no hold, no stay credit) left
// 18 % of traversal 2 to 257 inferences.
TEST_CASE("office-static: traversal 2 closes visually all but in full, none wrong, and CAT-Graph+ adds nothing",
          "[apps][localize][slow]") {
  const auto root = testing::TempDir("office_static");
  LocalizeCommandOptions o;
  const auto [d, in] = SimulateAndPrepare("office-static", root, o);
  const LocalizationResult plus = Localize(d, in.observations, *in.model, o.pipeline.front_end);
  o.pipeline.front_end.filter.inference.enabled = false;
  const LocalizationResult alone = Localize(d, in.observations, *in.model, o.pipeline.front_end);

  int second = 0, closed = 0;
  for (const LoopClosure& c : plus.closures) {
    CAPTURE(c.frame, c.matched_frame, c.error_m);
    CHECK(c.error_m <= 1.0);
    CHECK(c.kind == ClosureKind::kVisual);
    closed += d.frames.at(static_cast<std::size_t>(c.frame)).traversal == 2 ? 1 : 0;
  }
  for (const DatasetFrame& f : d.frames) second += f.traversal == 2 ? 1 : 0;
  INFO(closed << " of " << second << " traversal-2 frames closed visually");
  CHECK(closed >= 0.99 * second);
  REQUIRE(plus.closures.size() == alone.closures.size());
  for (std::size_t i = 0; i < plus.closures.size(); ++i) {
    CHECK(plus.closures[i].frame == alone.closures[i].frame);
    CHECK(plus.closures[i].matched_frame == alone.closures[i].matched_frame);
    CHECK(plus.closures[i].hypothesis == alone.closures[i].hypothesis);
  }
  REQUIRE(plus.frames.size() == alone.frames.size());
  for (std::size_t k = 0; k < plus.frames.size(); ++k) {
    CHECK(plus.frames[k].best.value == alone.frames[k].best.value);
  }
  CHECK(plus.discarded_inferences.empty());
  std::filesystem::remove_all(root);
}

// The split-path scenario with the defaults: the second traversal
// leaves the route for a parallel corridor and comes back. At the detour's
// corners, particles turned against corners of traversal 1 driven the other
// way round match the turn's shape; the forward camera saw none of what
// those nodes saw, so their hypothesis is no visual closure. Before that
// rule (2026-12-03) 49 wrong ones (up to 7.9 m) were made there. Table III's
// defaults cell (d_tot 1 m, d_loc 2 m): no false inference. Nor any
// inference at all since the robot stays on the map through the weak frames
// (2026-12-04): the mapped parts of traversal 2 close visually, and the
// detour's inferences fail local and total-path validation
// (docs/catgraph-plus.md, Table III).
TEST_CASE("office-split: no wrong visual closure at the detour's corners and no false inference",
          "[apps][localize][slow]") {
  const auto root = testing::TempDir("office_split");
  LocalizeCommandOptions o;
  const auto [d, in] = SimulateAndPrepare("office-split", root, o);
  const LocalizationResult result = Localize(d, in.observations, *in.model, o.pipeline.front_end);
  int visual = 0, inferred = 0;
  for (const LoopClosure& c : result.closures) {
    CAPTURE(c.frame, c.matched_frame, c.error_m);
    CHECK(c.error_m <= 1.0);
    (c.kind == ClosureKind::kVisual ? visual : inferred) += 1;
  }
  // The mapped parts of traversal 2 still close (1127 at filter seed 1).
  INFO(visual << " visual and " << inferred << " inferred closures");
  CHECK(visual > 1000);
  std::filesystem::remove_all(root);
}

// `catgraph demo` end to end (README's first command): it simulates
// office-change and maps it. On its outputs, the front end's acceptance
// with the defaults (the vocabulary trained on traversal 1, CAT-Graph+ over
// both traversals), the mapping outputs, then the SAD baseline on the same data.
TEST_CASE("demo on office-change: visual closures outside the changed region, inferred ones inside, none wrong, "
          "the corrected map",
          "[apps][localize][map][slow]") {
  const auto root = testing::TempDir("demo_office_change");
  const Result demo = Run({"demo", "-o", root.string(), "--quiet"});
  INFO(demo.out << demo.err);
  REQUIRE(demo.status == 0);
  CHECK(demo.out.find("catgraph demo: office-change, 3049 frames") != std::string::npos);
  const auto data = root / "office-change", out = root / "map";
  const Dataset d = ReadDataset(data);
  std::ifstream in(out / "closures.json");
  const auto closures = nlohmann::json::parse(in);
  std::vector<bool> closed(d.frames.size(), false), inferred_at(d.frames.size(), false);
  double sum = 0.0, worst = 0.0, worst_inferred = 0.0, sum_inferred = 0.0;
  int visual = 0, inferred = 0;
  std::set<int> visual_ids;
  for (const auto& c : closures) {
    for (const char* key : {"id", "frame", "matched_frame", "kind", "hypothesis", "error_m"}) CHECK(c.contains(key));
    const double e = c.at("error_m").get<double>();
    // Both traversals run the same way round: no closure faces backwards.
    CHECK(std::abs(c.at("relative_pose")[2].get<double>()) < std::numbers::pi / 2);
    if (c.at("kind") == "inferred") {
      // CAT-Graph+ (the default): hangs from one visual closure, validated
      // by a later one; never wrong by more than a metre.
      ++inferred;
      REQUIRE(c.at("parents").size() == 2);
      CHECK(visual_ids.count(c.at("parents")[0].get<int>()) == 1);
      CHECK(c.at("parents")[1].get<int>() > c.at("parents")[0].get<int>());
      worst_inferred = std::max(worst_inferred, e);
      sum_inferred += e;
      inferred_at.at(c.at("frame").get<std::size_t>()) = true;
      continue;
    }
    CHECK(c.at("kind") == "visual");
    visual_ids.insert(c.at("id").get<int>());
    ++visual;
    CHECK(c.at("hypothesis").get<double>() > 0.8);
    sum += e;
    worst = std::max(worst, e);
    closed.at(c.at("frame").get<std::size_t>()) = true;
  }
  // CAT-Graph+'s acceptance: the changed region covered by inferences, mean
  // error <= 0.3 m, none beyond 0.5 m (the paper: 0.24 m, all < 0.4 m).
  REQUIRE(inferred > 0);
  CHECK(sum_inferred / inferred <= 0.3);
  CHECK(worst_inferred <= 0.5);
  int outside = 0, outside_closed = 0, inside = 0, inside_closed = 0, inside_inferred = 0;
  for (std::size_t k = 0; k < d.frames.size(); ++k) {
    if (d.frames[k].traversal != 2) continue;
    (d.frames[k].changed ? inside : outside) += 1;
    (d.frames[k].changed ? inside_closed : outside_closed) += closed[k] ? 1 : 0;
    inside_inferred += d.frames[k].changed && inferred_at[k] ? 1 : 0;
  }
  CHECK(inside_inferred >= 0.7 * inside);
  REQUIRE(visual > 0);
  CHECK(outside_closed >= 0.6 * outside);
  CHECK(inside_closed <= 0.1 * inside);  // the paper's Fig. 7: rare where the place changed
  CHECK(worst <= 1.0);
  CHECK(sum / visual <= 0.25);
  CHECK(std::filesystem::exists(out / "hypotheses.csv"));
  CHECK(std::filesystem::exists(out / "graph.g2o"));
  CHECK(std::filesystem::exists(out / "localization.png"));
  CHECK(std::filesystem::exists(out / "discarded_inferences.json"));

  // The corrected map and its report.
  std::ifstream report_in(out / "report.json");
  const auto report = nlohmann::json::parse(report_in);
  for (const char* key : {"frames", "method", "hierarchy", "solves", "accepted", "rejected", "closures_by_kind",
                          "ate_odometry", "ate_corrected", "turned_off", "closures"}) {
    CHECK(report.contains(key));
  }
  REQUIRE(report.at("closures").size() == closures.size());
  std::map<int, bool> accepted_of;
  for (const auto& c : report.at("closures")) {
    for (const char* key : {"id", "kind", "frame", "matched_frame", "switch", "weight", "accepted", "error_m"}) {
      CHECK(c.contains(key));
    }
    accepted_of[c.at("id").get<int>()] = c.at("accepted").get<bool>();
  }
  // Cascade: no accepted child of a rejected parent.
  for (const auto& c : report.at("closures")) {
    if (c.at("kind") != "inferred" || !c.at("accepted").get<bool>()) continue;
    for (const auto& parent : c.at("parents")) CHECK(accepted_of.at(parent.get<int>()));
  }
  // The map is better than odometry alone, and close to the truth.
  const double ate_odometry = report.at("ate_odometry").at("rmse_m").get<double>();
  const double ate_corrected = report.at("ate_corrected").at("rmse_m").get<double>();
  CHECK(ate_corrected < 0.25 * ate_odometry);
  CHECK(ate_corrected < 0.25);
  for (const char* file : {"corrected.g2o", "corrected_accepted.g2o", "trajectory.tum", "groundtruth.tum", "index.html",
                           "map.svg"}) {
    CHECK(std::filesystem::exists(out / file));
  }
  // evo's reading of the two TUM files: pairs by timestamp, and after a rigid
  // alignment (evo_ape -a) the same ATE as report.json.
  const auto estimate = ReadTumAsEvo(out / "trajectory.tum"), truth = ReadTumAsEvo(out / "groundtruth.tum");
  REQUIRE(estimate.size() == report.at("frames").get<std::size_t>());
  REQUIRE(truth.size() == estimate.size());
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> pairs;
  for (std::size_t i = 0; i < estimate.size(); ++i) {
    CHECK(estimate[i][0] == Approx(d.frames[i].timestamp_s).margin(1e-9));
    const auto match = std::find_if(truth.begin(), truth.end(),
                                    [&](const auto& t) { return std::abs(t[0] - estimate[i][0]) < 0.01; });
    REQUIRE(match != truth.end());
    pairs.emplace_back(Eigen::Vector2d(estimate[i][1], estimate[i][2]), Eigen::Vector2d((*match)[1], (*match)[2]));
  }
  CHECK(RigidAlignedRmse(pairs) == Approx(ate_corrected).epsilon(1e-3));
  CheckNonTrivialImage(out / "map.png");
  CheckNonTrivialImage(out / "localization.png");

  // The baseline on the same data: its best threshold admits no false match
  // and almost nothing where the furniture moved.
  const Result sad = Run({"sad-match", data.string(), "-o", (root / "sad").string()});
  INFO(sad.out << sad.err);
  REQUIRE(sad.status == 0);
  const Csv matches = ReadCsv(root / "sad" / "matches.csv");
  CHECK(matches.header == "query_frame,template_frame,difference,shift_px,error_m,changed,accepted");
  int accepted = 0, accepted_changed = 0, changed_queries = 0;
  for (const auto& f : matches.rows) {
    REQUIRE(f.size() == 7);
    const bool is_changed = f[5] == "1", is_accepted = f[6] == "1";
    changed_queries += is_changed;
    accepted += is_accepted;
    accepted_changed += is_changed && is_accepted;
    if (is_accepted) CHECK(std::stod(f[4]) <= 1.0);
  }
  CHECK(accepted > 0);
  CHECK(accepted_changed <= 0.1 * changed_queries);
  CHECK(std::filesystem::exists(root / "sad" / "sad.png"));

  // False visual matches at the source. The flagged closures and
  // their children in report.json ...
  const auto injected_dir = root / "injected";
  const Result map = Run({"map", data.string(), "-o", injected_dir.string(), "--inject-false-visual", "3", "--seed",
                          "2", "--quiet"});
  INFO(map.out << map.err);
  REQUIRE(map.status == 0);
  std::ifstream injected_in(injected_dir / "report.json");
  const auto injected_report = nlohmann::json::parse(injected_in);
  REQUIRE(injected_report.contains("injected_false_visual"));
  const auto& injection = injected_report.at("injected_false_visual");
  CHECK(injection.at("count") == 3);
  CHECK(injection.at("matches").size() == 3);
  // The first solve: each pair brought its children, and every child of a
  // rejected false parent was turned off.
  CHECK(injection.at("false_closures") == 6);
  CHECK(injection.at("false_closures_rejected") == 6);
  CHECK(injection.at("children").get<int>() >= 3 * 20);
  CHECK(injection.at("children_of_rejected_accepted") == 0);
  // Feedback: the front end ran again with the rejected visual closures
  // vetoed, so the final map has the false closures, vetoed and rejected,
  // and no inferred closure hanging from them.
  REQUIRE(injected_report.at("feedback").at("reruns").get<int>() >= 1);
  const auto vetoed_frames = injected_report.at("feedback").at("vetoed_frames").get<std::set<int>>();
  std::set<int> false_ids;
  for (const auto& c : injected_report.at("closures")) {
    if (!c.value("injected", false)) continue;
    false_ids.insert(c.at("id").get<int>());
    CHECK(c.at("error_m").get<double>() >= 2.0);
    CHECK(c.value("vetoed", false));
    CHECK(vetoed_frames.count(c.at("frame").get<int>()) == 1);
    CHECK_FALSE(c.at("accepted").get<bool>());
  }
  CHECK(false_ids.size() == 6);
  for (const auto& c : injected_report.at("closures")) {
    if (c.at("kind") != "inferred") continue;
    for (const auto& parent : c.at("parents")) CHECK(false_ids.count(parent.get<int>()) == 0);
  }

  // ... and what the hierarchy buys (docs/mapping.md): cascade and coupled
  // turn off every child of a rejected false parent and the map is as good
  // as without the injection; under flat, children survive and cost.
  const auto experiment = root / "experiment";
  const Result run = Run({"hierarchy-experiment", data.string(), "-o", experiment.string(), "--seeds", "1"});
  INFO(run.out << run.err);
  REQUIRE(run.status == 0);
  const Csv table = ReadCsv(experiment / "hierarchy-experiment.csv");
  CHECK(table.header ==
        "seed,hierarchy,false_closures,false_closures_rejected,children,children_accepted,children_of_rejected,"
        "children_of_rejected_accepted,children_turned_off,accepted_children_error_max_m,ate_without_m,ate_with_m,"
        "ate_oracle_m,ate_ratio,solves,reruns");
  std::map<std::string, std::vector<std::string>> row_of;
  for (const auto& f : table.rows) {
    REQUIRE(f.size() == 16);
    row_of[f[1]] = f;
  }
  REQUIRE(row_of.size() == 3);
  for (const auto& [policy, f] : row_of) {
    CAPTURE(policy);
    CHECK(f[2] == "20");
    CHECK(f[3] == "20");  // every false visual closure rejected
    const double without = std::stod(f[10]), with = std::stod(f[11]), oracle = std::stod(f[12]);
    if (policy == "flat") {
      CHECK(std::stoi(f[7]) > 0);   // children of rejected parents survive ...
      CHECK(with > 1.5 * oracle);   // ... and cost
      CHECK(f[15] == "0");          // no feedback without a hierarchy
    } else {
      CHECK(std::stoi(f[15]) >= 1);  // the front end re-run with the false closures vetoed
      CHECK(std::stoi(f[7]) == 0);
      CHECK(std::stoi(f[8]) > 0);   // the hierarchy, not the back end alone, turned them off
      CHECK(with <= 1.1 * without);
      // Feedback does what vetoing the false closures from the start does,
      // or better: it also vetoes the other closures the back end rejected
      // (coupled, filter seed 1, since 2026-12-04: frames 3045-3048 at the
      // map's end, 0.6-0.8 m off, as well; 0.090 m against the oracle's
      // 0.101 m and 0.101 m without injection; cascade 0.090 m, oracle
      // 0.089 m).
      CHECK(with <= 1.02 * oracle);
    }
  }
  CHECK(std::filesystem::exists(experiment / "hierarchy-experiment.md"));
  std::filesystem::remove_all(root);
}

// Every command of the test above on a 625-frame office
// (tests/fixtures/office-change-short.yaml), with the accuracy each must
// reach. The short loop leaves CAT-Graph only a few metres before the change; under
// the earlier defaults (2026-12-03) it made false visual closures there, now
// none is over 1 m. The false closures the back end must reject are
// injected, in the hierarchy experiment at the end.
TEST_CASE("every stage of the demo on a short office: no wrong visual closure, the changed corridor inferred, the "
          "map corrected, injected false closures rejected",
          "[apps][localize][map][slow]") {
  const auto root = testing::TempDir("demo_short");
  const Result missing = Run({"demo", "-o", (root / "none").string(), "--scenario", "no-such.yaml", "--quiet"});
  CHECK(missing.status == 1);
  CHECK(missing.err.find("no-such.yaml") != std::string::npos);
  CHECK_FALSE(std::filesystem::exists(root / "none"));
  const Result demo = Run({"demo", "-o", root.string(), "--scenario",
                           testing::Fixture("office-change-short.yaml").string(), "--quiet"});
  INFO(demo.out << demo.err);
  REQUIRE(demo.status == 0);
  CHECK(demo.out.find("catgraph demo: office-change-short, 625 frames over two traversals") != std::string::npos);
  const auto data = root / "office-change-short", out = root / "map";
  std::ifstream report_in(out / "report.json");
  const auto report = nlohmann::json::parse(report_in);
  std::map<int, bool> accepted_of;
  int visual = 0, inferred = 0;
  for (const auto& c : report.at("closures")) {
    accepted_of[c.at("id").get<int>()] = c.at("accepted").get<bool>();
  }
  for (const auto& c : report.at("closures")) {
    const double e = c.at("error_m").get<double>();
    const bool accepted = c.at("accepted").get<bool>();
    CAPTURE(c.at("id").get<int>(), e);
    if (accepted) CHECK(e <= 1.0);
    if (c.at("kind") == "inferred") {
      ++inferred;
      CHECK(e <= 0.5);
      REQUIRE(c.at("parents").size() == 2);
      // Cascade: no accepted child of a rejected parent.
      if (accepted) CHECK(accepted_of.at(c.at("parents")[0].get<int>()));
    } else {
      ++visual;
      CHECK(e <= 1.0);
    }
  }
  CHECK(visual > 20);
  CHECK(inferred > 50);
  const double ate_odometry = report.at("ate_odometry").at("rmse_m").get<double>();
  const double ate_corrected = report.at("ate_corrected").at("rmse_m").get<double>();
  CHECK(ate_corrected < 0.5 * ate_odometry);
  CheckNonTrivialImage(out / "map.png");
  CheckNonTrivialImage(out / "localization.png");

  // The paper's filter exactly (--preset paper): a forward view down a
  // corridor shares its far half with every place behind it, and with no
  // offset, gate or recognition rule the spec's filter takes such places
  // for revisits, which the defaults above never do. Its options.yaml runs
  // it again, closure for closure.
  const Result paper = Run({"localize", data.string(), "-o", (root / "paper").string(), "--preset", "paper", "--quiet"});
  INFO(paper.out << paper.err);
  REQUIRE(paper.status == 0);
  int paper_wrong = 0;
  std::ifstream paper_in(root / "paper" / "closures.json");
  for (const auto& c : nlohmann::json::parse(paper_in)) {
    if (c.at("kind") == "visual" && c.at("error_m").get<double>() > 1.0) ++paper_wrong;
  }
  CHECK(paper_wrong > 20);
  const Result again = Run({"localize", data.string(), "-o", (root / "again").string(), "--options",
                            (root / "paper" / "options.yaml").string(), "--quiet"});
  REQUIRE(again.status == 0);
  CHECK(testing::ReadText(root / "again" / "closures.json") == testing::ReadText(root / "paper" / "closures.json"));
  CHECK(testing::ReadText(root / "again" / "options.yaml") == testing::ReadText(root / "paper" / "options.yaml"));

  const Result sad = Run({"sad-match", data.string(), "-o", (root / "sad").string()});
  INFO(sad.out << sad.err);
  REQUIRE(sad.status == 0);
  // One query per second traversal frame in two (its default stride), each
  // against the first traversal's templates.
  const Csv matches = ReadCsv(root / "sad" / "matches.csv");
  CHECK(matches.rows.size() == 98);
  int sad_accepted = 0;
  for (const auto& f : matches.rows) {
    REQUIRE(f.size() == 7);
    if (f[6] != "1") continue;
    ++sad_accepted;
    CHECK(std::stod(f[4]) <= 1.0);  // accepted at the best threshold with no false match
  }
  CHECK(sad_accepted > 0);

  // The evidence behind the new-place offsets: one row per traversal-2
  // frame; where the place did not change, its true place scores above its
  // best look-alike a few metres away in most frames.
  const Result evidence = Run({"evidence", data.string(), "-o", (root / "evidence").string(), "--quiet"});
  INFO(evidence.out << evidence.err);
  REQUIRE(evidence.status == 0);
  CHECK(std::filesystem::exists(root / "evidence" / "summary.md"));
  const Csv rows = ReadCsv(root / "evidence" / "evidence.csv");
  CHECK(rows.header == "frame,words,changed,self,true_place,near,far");
  CHECK(rows.rows.size() == 195);
  int unchanged = 0, true_wins = 0;
  for (const auto& f : rows.rows) {
    REQUIRE(f.size() == 7);
    if (f[2] != "0" || f[4].empty() || f[5].empty()) continue;  // empty: no such map frame
    ++unchanged;
    true_wins += std::stod(f[4]) > std::stod(f[5]) ? 1 : 0;
  }
  CHECK(unchanged > 20);
  CHECK(true_wins >= 0.9 * unchanged);

  const Result sweep = Run({"inference-sweep", data.string(), "-o", (root / "sweep").string(), "--d-tot", "1",
                            "--d-loc", "2", "--back-end", "--quiet"});
  INFO(sweep.out << sweep.err);
  REQUIRE(sweep.status == 0);
  // The Table III sweep, one cell at the defaults, with the back end in the
  // loop: each cell is mapped as catgraph map does, so its front end's last
  // run is the map's (the same inferences, the same re-runs).
  const Csv cells = ReadCsv(root / "sweep" / "sweep.csv");
  CHECK(cells.header == "d_tot_m,d_loc_m,inferred,false,largest_error_m,mean_false_error_m,mean_error_m,"
                        "discarded,false_accepted,reruns,dropped");
  REQUIRE(cells.rows.size() == 1);
  REQUIRE(cells.rows[0].size() == 11);
  CHECK(std::stoi(cells.rows[0][2]) == inferred);
  CHECK(cells.rows[0][3] == "0");
  CHECK(cells.rows[0][8] == "0");
  CHECK(std::stoi(cells.rows[0][9]) == report.at("feedback").at("reruns").get<int>());

  // Injected false matches: all rejected; none of their children kept by
  // cascade and coupled. (Flat's back end rejects all 16 here too; it keeps
  // some in the synthetic graphs of tests/hierarchy.)
  const auto experiment = root / "experiment";
  const Result run = Run({"hierarchy-experiment", data.string(), "-o", experiment.string(), "--seeds", "1",
                          "--inject-false-visual", "3"});
  INFO(run.out << run.err);
  REQUIRE(run.status == 0);
  const Csv table = ReadCsv(experiment / "hierarchy-experiment.csv");
  REQUIRE(table.rows.size() == 3);
  for (const auto& f : table.rows) {
    CAPTURE(f[1]);
    REQUIRE(f.size() == 16);
    CHECK(f[2] == "6");
    CHECK(f[3] == "6");
    if (f[1] != "flat") CHECK(std::stoi(f[7]) == 0);
    // The run without injection is the demo's map (cascade, filter seed 1),
    // feedback re-runs included: they must not bring the false matches back.
    if (f[1] == "cascade") CHECK(std::stod(f[10]) == Approx(ate_corrected).margin(1e-4));
  }
  std::filesystem::remove_all(root);
}

// The short office at fewer frames per second: what the sanitizer build runs
// of the mapping pipeline, where the [slow] tests above are left to the
// release build (tests/CMakeLists.txt). These check that every stage runs and
// writes what it promises; the tests above check accuracy. At 3 frames/s
// (375 frames) CAT-Graph+ still infers closures; at 2.5 (313 frames) false
// visual matches still fit for the hierarchy experiment.
std::filesystem::path WriteSmallOffice(const std::filesystem::path& root, const std::string& frame_rate_hz) {
  std::string scenario = testing::ReadText(testing::Fixture("office-change-short.yaml"));
  const std::string rate = "frame_rate_hz: 5.0";
  REQUIRE(scenario.find(rate) != std::string::npos);
  scenario.replace(scenario.find(rate), rate.size(), "frame_rate_hz: " + frame_rate_hz);
  std::ofstream(root / "office-small.yaml") << scenario;
  return root / "office-small.yaml";
}

TEST_CASE("demo runs on a 375-frame office and writes its outputs", "[apps][localize][map][small-office]") {
  const auto root = testing::TempDir("demo_small");
  const Result demo =
      Run({"demo", "-o", root.string(), "--scenario", WriteSmallOffice(root, "3.0").string(), "--quiet"});
  INFO(demo.out << demo.err);
  REQUIRE(demo.status == 0);
  CHECK(demo.out.find("375 frames over two traversals") != std::string::npos);
  const auto out = root / "map";
  std::ifstream report_in(out / "report.json");
  const auto report = nlohmann::json::parse(report_in);
  int visual = 0, inferred = 0;
  for (const auto& c : report.at("closures")) {
    if (c.at("kind") == "inferred") {
      ++inferred;
      CHECK(c.at("parents").size() == 2);
    } else {
      ++visual;
    }
  }
  CHECK(visual > 0);
  CHECK(inferred > 0);
  for (const char* file : {"corrected.g2o", "trajectory.tum", "groundtruth.tum", "index.html"}) {
    CHECK(std::filesystem::exists(out / file));
  }
  CheckNonTrivialImage(out / "map.png");
  CheckNonTrivialImage(out / "localization.png");
  std::filesystem::remove_all(root);
}

TEST_CASE("sad-match, evidence, inference-sweep and hierarchy-experiment run on a 313-frame office and write "
          "their tables",
          "[apps][localize][small-office]") {
  const auto root = testing::TempDir("analysis_small");
  const auto data = root / "office";
  const Result simulate =
      Run({"simulate", "--scenario", WriteSmallOffice(root, "2.5").string(), "-o", data.string(), "--quiet"});
  INFO(simulate.out << simulate.err);
  REQUIRE(simulate.status == 0);
  REQUIRE(ReadDataset(data).frames.size() == 313);
  for (const std::vector<std::string>& command :
       {std::vector<std::string>{"sad-match", data.string(), "-o", (root / "sad").string()},
        {"evidence", data.string(), "-o", (root / "evidence").string(), "--quiet"},
        {"inference-sweep", data.string(), "-o", (root / "sweep").string(), "--d-tot", "1", "--d-loc", "2",
         "--back-end", "--quiet"},
        {"hierarchy-experiment", data.string(), "-o", (root / "experiment").string(), "--seeds", "1",
         "--inject-false-visual", "2", "--hierarchies", "cascade"}}) {
    const Result r = Run(command);
    INFO(command[0] << ": " << r.out << r.err);
    CHECK(r.status == 0);
  }
  CHECK(ReadCsv(root / "sad" / "matches.csv").rows.size() > 0);
  CHECK(ReadCsv(root / "evidence" / "evidence.csv").rows.size() > 0);
  CHECK(ReadCsv(root / "sweep" / "sweep.csv").rows.size() == 1);
  CHECK(ReadCsv(root / "experiment" / "hierarchy-experiment.csv").rows.size() == 1);
  std::filesystem::remove_all(root);
}

}  // namespace
}  // namespace catgraph
