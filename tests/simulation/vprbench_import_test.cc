// The VPR-Bench converter on the shared corridor set: real images, made-up
// route, index alignment kept.
#include <filesystem>

#include "tests/catch.h"

#include "backend/io/dataset.h"
#include "backend/io/file_error.h"
#include "simulation/vprbench_import.h"
#include "tests/test_support.h"

namespace catgraph {
namespace {

TEST_CASE("the corridor set converts to a dataset whose query frame i sits at reference frame i",
          "[simulation][vprbench]") {
  const auto source = std::filesystem::path(CATGRAPH_SHARED_DATASETS) / "images" / "corridor_vprbench";
  if (!std::filesystem::is_directory(source)) {
    WARN("skipped: the corridor set is not at " << source.string() << " (set -DCATGRAPH_SHARED_DATASETS=...)");
    return;
  }
  const auto out = testing::TempDir("vprbench");
  VprBenchImportOptions options;
  const auto summary = ImportVprBench(source, out, options);
  CHECK(summary.reference_frames == 111);
  CHECK(summary.query_frames == 111);
  const Dataset d = ReadDataset(out);
  REQUIRE(d.frames.size() == 222);
  CHECK(d.Traversals() == std::vector<int>{1, 2});
  CHECK(d.meta.synthetic_odometry);
  CHECK(d.meta.synthetic_ground_truth);
  CHECK_FALSE(d.meta.synthetic_images);
  CHECK(d.meta.camera.width_px == 160);
  CHECK(d.meta.camera.height_px == 120);
  for (std::size_t i = 0; i < 111; i += 10) {
    const Pose2 reference = InterpolatePose(d.ground_truth, d.frames[i].timestamp_s);
    const Pose2 query = InterpolatePose(d.ground_truth, d.frames[111 + i].timestamp_s);
    INFO("frame " << i);
    CHECK(reference.x() == Approx(0.5 * static_cast<double>(i)).margin(1e-6));
    CHECK(query.x() == Approx(reference.x()).margin(1e-6));
    CHECK(std::abs(query.y() - reference.y()) < 0.05);
  }
  // Odometry drifts but stays close over the 55 m corridor.
  const Pose2 end_truth = InterpolatePose(d.ground_truth, d.frames[110].timestamp_s);
  const Pose2 end_odometry = InterpolatePose(d.odometry, d.frames[110].timestamp_s);
  const Pose2 start_truth = InterpolatePose(d.ground_truth, d.frames[0].timestamp_s);
  const Pose2 start_odometry = InterpolatePose(d.odometry, d.frames[0].timestamp_s);
  const double odometry_length = (start_odometry.Between(end_odometry)).translation().norm();
  const double true_length = (start_truth.Between(end_truth)).translation().norm();
  CHECK(odometry_length == Approx(true_length).epsilon(0.01));
  std::filesystem::remove_all(out);
}

TEST_CASE("converting a folder without ref/ names what is missing", "[simulation][vprbench][bad-input]") {
  const auto dir = testing::TempDir("vprbench_bad");
  try {
    ImportVprBench(dir, dir / "out", {});
    FAIL("no error");
  } catch (const FileError& e) {
    CHECK_THAT(e.what(), Catch::Contains("ref: no such directory; expected a folder of images"));
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace catgraph
