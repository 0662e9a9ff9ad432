// Solves a g2o (or TORO, iSAM) pose graph robustly and writes the corrected
// graph with every loop closure's decision.
//
//   solve_g2o INPUT.g2o OUTPUT.g2o
#include <cstdio>
#include <exception>

#include <catgraph/backend/io/graph_io.h>
#include <catgraph/backend/pose_graph_optimizer.h>

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s INPUT.g2o OUTPUT.g2o\n", argv[0]);
    return 2;
  }
  try {
    const catgraph::GraphFile input = catgraph::ReadGraphFile(argv[1]);
    // The defaults: switchable constraints gated at the chi2 quantile, the
    // noise scale measured from the graph, refinement and readmission.
    const catgraph::PoseGraphOptimization solved = catgraph::OptimizePoseGraph(input.graph);
    if (!solved.summary.IsUsable()) {
      std::fprintf(stderr, "%s\n", solved.summary.BriefReport().c_str());
      return 1;
    }
    std::printf("%s\n", solved.summary.BriefReport().c_str());
    std::printf("%zu loop closures accepted, %zu rejected\n", solved.accepted, solved.rejected);
    for (const catgraph::ClosureDecision& c : solved.closures) {
      if (!c.accepted) std::printf("  rejected %lld -> %lld (weight %.3f)\n",
                                   static_cast<long long>(c.from.value()), static_cast<long long>(c.to.value()),
                                   c.weight);
    }
    // The decisions travel with the graph (#CATGRAPH_DECISION lines).
    catgraph::WriteG2oFile(solved.graph, argv[2]);
  } catch (const std::exception& e) {  // FileError names the file and the line
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
