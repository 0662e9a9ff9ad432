// The dataset format: a written dataset reads back, and every inconsistency
// is a FileError naming the file and the line.
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "tests/catch.h"

#include "backend/io/dataset.h"
#include "backend/io/file_error.h"
#include "tests/test_support.h"

namespace catgraph {
namespace {

// Three frames over two traversals, odometry and ground truth from 0 to 1 s.
Dataset SmallDataset(const std::filesystem::path& root) {
  Dataset d;
  d.root = root;
  std::filesystem::create_directories(root / "images");
  for (int i = 0; i < 3; ++i) {
    const std::string image = "images/00000" + std::to_string(i) + ".png";
    std::ofstream(root / image) << "not really a png";
    d.frames.push_back({0.25 * (i + 1), image, i < 2 ? 1 : 2, i == 2, i == 2 ? 0.5 : 0.0});
    d.meta.frame_changed.push_back(i == 2);
  }
  d.odometry = {{0.0, Pose2(0, 0, 0)}, {0.5, Pose2(1, 0, 0)}, {1.0, Pose2(2, 0, 0.5)}};
  d.ground_truth = d.odometry;
  d.meta.scenario = "unit";
  d.meta.changed_regions.push_back({"r", "furniture", {{0, 0}, {1, 0}, {1, 1}}});
  return d;
}

std::string ErrorReading(const std::filesystem::path& root) {
  try {
    ReadDataset(root);
  } catch (const FileError& e) {
    return e.what();
  }
  return "no error";
}

void Replace(const std::filesystem::path& file, const std::string& from, const std::string& to) {
  std::string text = testing::ReadText(file);
  REQUIRE(text.find(from) != std::string::npos);
  text.replace(text.find(from), from.size(), to);
  std::ofstream(file, std::ios::binary | std::ios::trunc) << text;
}

TEST_CASE("a written dataset reads back", "[io][dataset]") {
  const auto root = testing::TempDir("dataset_roundtrip");
  const Dataset written = SmallDataset(root);
  WriteDatasetTables(written);
  const Dataset d = ReadDataset(root);
  REQUIRE(d.frames.size() == 3);
  CHECK(d.frames[2].traversal == 2);
  CHECK(d.frames[2].changed);
  CHECK(d.frames[2].changed_fraction == 0.5);
  CHECK(d.Traversals() == std::vector<int>{1, 2});
  CHECK(d.odometry.size() == 3);
  CHECK(d.ground_truth.size() == 3);
  CHECK(d.meta.scenario == "unit");
  CHECK(d.meta.changed_regions.at(0).polygon.size() == 3);
  CHECK(d.ImagePath(1) == root / "images/000001.png");
  // Interpolation between the samples, heading along the shorter arc.
  const Pose2 mid = InterpolatePose(d.odometry, 0.75);
  CHECK(mid.x() == Approx(1.5));
  CHECK(mid.theta() == Approx(0.25));
  CHECK_THROWS_AS(InterpolatePose(d.odometry, 1.5), std::out_of_range);
  std::filesystem::remove_all(root);
}

TEST_CASE("inconsistent datasets are errors naming the file and the line", "[io][dataset][bad-input]") {
  const auto root = testing::TempDir("dataset_bad");
  auto fresh = [&] {
    std::filesystem::remove_all(root);
    WriteDatasetTables(SmallDataset(root));
  };
  fresh();
  std::filesystem::remove(root / "images/000001.png");
  CHECK_THAT(ErrorReading(root), Catch::Contains("frames.csv:3: image 'images/000001.png' does not exist"));

  fresh();
  Replace(root / "frames.csv", "0.500000,", "0.100000,");
  CHECK_THAT(ErrorReading(root), Catch::Contains("frames.csv:3: timestamp 0.100000 is not after the previous frame's"));

  fresh();
  Replace(root / "odometry.csv", "\n1.000000,", "\n0.600000,");
  CHECK_THAT(ErrorReading(root), Catch::Contains("frames.csv:4: frame timestamp 0.750000 lies outside the time range [0.000000, 0.600000] of odometry.csv"));

  // Files that lead out of the folder through a symbolic link, and files that
  // are no regular files, are refused by name.
  fresh();
  const auto outside = testing::TempDir("dataset_outside");
  std::filesystem::copy_file(root / "images/000001.png", outside / "x.png");
  std::filesystem::remove(root / "images/000001.png");
  std::filesystem::create_symlink(outside / "x.png", root / "images/000001.png");
  CHECK_THAT(ErrorReading(root), Catch::Contains("frames.csv:3: image 'images/000001.png' is a symbolic link (or lies "
                                                 "below one) that leads out of the dataset folder"));
  fresh();
  std::filesystem::rename(root / "images", outside / "images");
  std::filesystem::create_directory_symlink(outside / "images", root / "images");
  CHECK_THAT(ErrorReading(root), Catch::Contains("frames.csv:2: image 'images/000000.png' is a symbolic link"));
  fresh();
  std::filesystem::rename(root / "odometry.csv", outside / "odometry.csv");
  std::filesystem::create_symlink(outside / "odometry.csv", root / "odometry.csv");
  CHECK_THAT(ErrorReading(root), Catch::Contains("odometry.csv: is a symbolic link that leads out of the dataset folder"));
  fresh();
  std::filesystem::remove(root / "images/000001.png");
  REQUIRE(::mkfifo((root / "images/000001.png").c_str(), 0600) == 0);
  CHECK_THAT(ErrorReading(root), Catch::Contains("frames.csv:3: image 'images/000001.png' is not a regular file"));
  fresh();
  std::filesystem::remove(root / "frames.csv");
  REQUIRE(::mkfifo((root / "frames.csv").c_str(), 0600) == 0);
  CHECK_THAT(ErrorReading(root), Catch::Contains("frames.csv: is not a regular file (a FIFO, device or socket)"));
  std::filesystem::remove_all(outside);
  // A link that stays inside the folder is followed.
  fresh();
  std::filesystem::rename(root / "images/000001.png", root / "images/real.png");
  std::filesystem::create_symlink("real.png", root / "images/000001.png");
  CHECK(ReadDataset(root).frames.size() == 3);

  // Ground truth that ends before the last frame: an input error, not an
  // interpolation failure deep inside a command.
  fresh();
  Replace(root / "groundtruth.csv", "\n1.000000,", "\n0.600000,");
  CHECK_THAT(ErrorReading(root), Catch::Contains("frames.csv:4: frame timestamp 0.750000 lies outside the time range [0.000000, 0.600000] of groundtruth.csv; expected every frame to have a ground-truth pose"));

  fresh();
  Replace(root / "odometry.csv", "\n0.500000,", "\n0.000000,");
  CHECK_THAT(ErrorReading(root), Catch::Contains("odometry.csv:3: timestamp 0.000000 is not after"));

  fresh();
  Replace(root / "frames.csv", "timestamp,image", "time,image");
  CHECK_THAT(ErrorReading(root), Catch::Contains("frames.csv:1: expected the header 'timestamp,image,traversal,changed[,changed_fraction]'; column 1 is 'time'"));
  // A foreign file's first line is not echoed beyond its first wrong column.
  fresh();
  Replace(root / "odometry.csv", "timestamp,x,y,theta", "timestamp,x,secret " + std::string(200, 's') + ",theta");
  const std::string foreign = ErrorReading(root);
  CHECK_THAT(foreign, Catch::EndsWith("; column 3 is 'secret " + std::string(57, 's') + "...'"));

  fresh();
  Replace(root / "groundtruth.csv", "1.000000,2.000000", "1.000000,abc");
  CHECK_THAT(ErrorReading(root), Catch::Contains("groundtruth.csv:4: row: expected a number for x, found 'abc'"));

  fresh();
  Replace(root / "meta.json", "\"frame_changed\": [\n  0,\n  0,\n  1\n ]", "\"frame_changed\": [0, 1, 1]");
  CHECK_THAT(ErrorReading(root), Catch::Contains("meta.json: frame_changed[1] disagrees with frames.csv row 3"));

  fresh();
  Replace(root / "meta.json", "\"format_version\": 1", "\"format_version\": 9");
  CHECK_THAT(ErrorReading(root), Catch::Contains("meta.json: format_version 9 is not supported"));

  // A number beyond int's range is an error, not a cast (found by fuzzing).
  fresh();
  Replace(root / "meta.json", "\"format_version\": 1", "\"format_version\": 1.06e130");
  CHECK_THAT(ErrorReading(root), Catch::Contains("meta.json: 'format_version' must be an integer from 0 to 1000000, not 1.06e+130"));

  fresh();
  Replace(root / "meta.json", "\"scenario\"", "\"scenario\" oops");
  CHECK_THAT(ErrorReading(root), Catch::Contains("meta.json:3: expected valid JSON"));

  fresh();
  Replace(root / "frames.csv", "images/000000.png", "../outside.png");
  CHECK_THAT(ErrorReading(root), Catch::Contains("frames.csv:2: image '../outside.png': expected a path relative to the dataset folder, inside it"));

  CHECK_THAT(ErrorReading(root / "nowhere"), Catch::Contains("no such directory; expected a dataset folder"));
  std::filesystem::remove_all(root);
}

}  // namespace
}  // namespace catgraph
