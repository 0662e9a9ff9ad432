// Localises a dataset (catgraph's folder layout: frames.csv, odometry.csv,
// images/; docs/dataset-format.md) with CAT-Graph and the holistic
// observation model, and prints the loop closures it made.
//
//   catgraph simulate --scenario office-change -o office   # or your own data
//   localize_dataset office
#include <cmath>
#include <cstdio>
#include <exception>

#include <catgraph/backend/io/dataset.h>
#include <catgraph/frontend/localization.h>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s DATASET\n", argv[0]);
    return 2;
  }
  try {
    const catgraph::Dataset dataset = catgraph::ReadDataset(argv[1]);
    catgraph::LocalizationOptions options;
    // The holistic model, calibrated on the dataset's first traversal.
    const catgraph::HolisticFrontEnd front_end = catgraph::PrepareHolistic(dataset, {}, options);
    const catgraph::LocalizationResult result =
        catgraph::Localize(dataset, front_end.observations, *front_end.model, options);
    int visual = 0, inferred = 0;
    for (const catgraph::LoopClosure& c : result.closures) {
      (c.kind == catgraph::ClosureKind::kVisual ? visual : inferred) += 1;
    }
    std::printf("%zu frames: %d visual closures, %d inferred by CAT-Graph+\n", result.frames.size(), visual,
                inferred);
    for (const catgraph::LoopClosure& c : result.closures) {
      std::printf("  %-8s frame %5d -> frame %5d", c.kind == catgraph::ClosureKind::kVisual ? "visual" : "inferred",
                  c.frame, c.matched_frame);
      if (!std::isnan(c.error_m)) std::printf("  (%.2f m from the true place)", c.error_m);
      std::printf("\n");
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
