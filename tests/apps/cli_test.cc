// The `catgraph` command run in process, exactly as main() runs it.
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "apps/commands.h"
#include "tests/test_support.h"

namespace catgraph {
namespace {

struct Result {
  int status;
  std::string out;
  std::string err;
};

Result Run(std::vector<std::string> args) {
  args.insert(args.begin(), "catgraph");
  std::vector<const char*> argv;
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
  CHECK(Run({"generate-graph", "-o", graph, "--poses", "1"}).status == 1);
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
  const auto info = nlohmann::json::parse(Run({"info", out, "--json"}).out);
  // One switch per loop closure, written with the graph.
  CHECK(info.at("switches") == info.at("loop_closures"));
  CHECK(info.at("switchable_edges") == info.at("loop_closures"));
  std::ifstream report_file(report);
  const auto full = nlohmann::json::parse(report_file);
  CHECK(full.at("closures").size() == j.at("accepted").get<std::size_t>() + j.at("rejected").get<std::size_t>());
  // --drop-rejected writes a graph without switches.
  REQUIRE(Run({"optimize", graph, "-o", out, "--drop-rejected"}).status == 0);
  CHECK(nlohmann::json::parse(Run({"info", out, "--json"}).out).at("switches") == 0);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace catgraph
