// What each libFuzzer target feeds a reader, as plain functions: the
// fuzzers call them, and tests/io/fuzz_regressions_test.cc runs every input
// a fuzzer ever crashed on (tests/fixtures/fuzz/TARGET/) through them. Each
// returns normally or throws FileError, the readers' one error type;
// anything else (another exception, a crash, a sanitizer report) is a bug.
// The first byte of an input picks the reader or format where a target has
// several; docs/fuzzing.md.
#ifndef CATGRAPH_FUZZ_FUZZ_INPUTS_H_
#define CATGRAPH_FUZZ_FUZZ_INPUTS_H_

#include <unistd.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>

#include "experiments/sweep.h"
#include "backend/io/closure_labels.h"
#include "backend/io/dataset.h"
#include "backend/io/file_error.h"
#include "backend/io/graph_io.h"
#include "backend/io/image_file.h"
#include "backend/io/trajectory_io.h"
#include "frontend/vocabulary.h"
#include "simulation/dataset_import.h"
#include "simulation/scenario.h"

namespace catgraph::fuzz {

// A folder of this process's own under the temporary directory, made once,
// for the readers that take paths.
inline const std::filesystem::path& ScratchDir() {
  static const std::filesystem::path dir = [] {
    auto d = std::filesystem::temp_directory_path() / ("catgraph_fuzz_" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  return dir;
}

inline void WriteFile(const std::filesystem::path& path, std::string_view bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// g2o, TORO and iSAM graphs. First byte: format (auto, g2o, TORO, iSAM) in
// its low two bits, a ".graph" name with bit 2. What was read is written.
inline void Graph(std::string_view input) {
  if (input.empty()) return;
  constexpr GraphFormat kFormats[] = {GraphFormat::kAuto, GraphFormat::kG2o, GraphFormat::kToro, GraphFormat::kIsam};
  const auto first = static_cast<unsigned char>(input[0]);
  ReadGraphOptions options;
  options.format = kFormats[first % 4];
  std::istringstream in{std::string(input.substr(1))};
  try {
    const GraphFile file = ReadGraph(in, (first & 4) ? "fuzz.graph" : "fuzz.g2o", options);
    std::ostringstream out;
    WriteG2o(file.graph, out);
  } catch (const FileError&) {
  }
}

// Trajectories (format auto, graph, poses, TUM in the low two bits) or, with
// bit 2, closure labels: the line readers of catgraph evaluate.
inline void Trajectory(std::string_view input) {
  if (input.empty()) return;
  constexpr TrajectoryFormat kFormats[] = {TrajectoryFormat::kAuto, TrajectoryFormat::kGraph,
                                           TrajectoryFormat::kPoses, TrajectoryFormat::kTum};
  const auto first = static_cast<unsigned char>(input[0]);
  std::istringstream in{std::string(input.substr(1))};
  try {
    if (first & 4) {
      ReadClosureLabels(in, "fuzz_labels.csv");
    } else {
      const AnyTrajectory t = ReadTrajectory(in, "fuzz.txt", kFormats[first % 4]);
      std::ostringstream out;
      WriteTum(t, out);
    }
  } catch (const FileError&) {
  }
}

// A simulator scenario file (the whole input).
inline void Scenario(std::string_view input) {
  try {
    ParseScenario(input, "fuzz.yaml", ScratchDir());
  } catch (const FileError&) {
  }
}

// A dataset folder: the first byte picks the file (frames.csv, odometry.csv,
// groundtruth.csv, meta.json) the rest replaces in a valid three-frame
// dataset. The valid dataset is written once per folder; each input rewrites
// one file and puts it back afterwards (most of a run was the file system).
inline void DatasetFolder(std::string_view input) {
  if (input.empty()) return;
  constexpr std::string_view kPoses =
      "timestamp,x,y,theta\n"
      "0.000000,0.0,0.0,0.0\n"
      "0.100000,0.1,0.0,0.0\n"
      "0.200000,0.2,0.0,0.1\n";
  struct File {
    const char* name;
    std::string_view valid;
  };
  constexpr File kFiles[] = {
      {"frames.csv",
       "timestamp,image,traversal,changed,changed_fraction\n"
       "0.000000,images/000000.png,1,0,0.0000\n"
       "0.100000,images/000001.png,1,0,0.0000\n"
       "0.200000,images/000002.png,2,1,0.5000\n"},
      {"odometry.csv", kPoses},
      {"groundtruth.csv", kPoses},
      {"meta.json", R"({"format_version": 1, "scenario": "fuzz", "seed": 1, "frame_changed": [0, 0, 1]})"}};
  const std::filesystem::path root = ScratchDir() / "dataset";
  if (!std::filesystem::exists(root / "meta.json")) {
    std::filesystem::create_directories(root / "images");
    for (const char* image : {"000000.png", "000001.png", "000002.png"}) WriteFile(root / "images" / image, "");
    for (const File& f : kFiles) WriteFile(root / f.name, f.valid);
  }
  const File& replaced = kFiles[static_cast<unsigned char>(input[0]) % 4];
  WriteFile(root / replaced.name, input.substr(1));
  try {
    const Dataset d = ReadDataset(root);
    PosesAtFrames(d, d.odometry);
  } catch (const FileError&) {
  }
  WriteFile(root / replaced.name, replaced.valid);
}

// A recording in one of `catgraph import`'s layouts. The first byte picks
// the file the rest replaces in a valid three-frame recording (0: KITTI's
// poses file, 1: its times.txt, 2: TUM's groundtruth.txt, 3: its rgb.txt,
// 4: a folder's pose CSV, 5: its times file), and so the layout imported.
inline void ImportRecording(std::string_view input) {
  if (input.empty()) return;
  struct File {
    ImportLayout layout;
    const char* name;
    std::string_view valid;
  };
  constexpr File kFiles[] = {
      {ImportLayout::kKitti, "kitti/poses.txt",
       "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1 0.1\n1 0 0 0 0 1 0 0 0 0 1 0.2\n"},
      {ImportLayout::kKitti, "kitti/times.txt", "0.0\n0.1\n0.2\n"},
      {ImportLayout::kTum, "tum/groundtruth.txt", "0.0 0 0 0 0 0 0 1\n0.1 0 0 0.1 0 0 0 1\n0.2 0 0 0.2 0 0 0 1\n"},
      {ImportLayout::kTum, "tum/rgb.txt", "0.0 rgb/0.png\n0.1 rgb/1.png\n0.2 rgb/2.png\n"},
      {ImportLayout::kFolder, "folder/poses.csv", "timestamp,x,y,theta\n0,0,0,0\n0.1,0.1,0,0\n0.2,0.2,0,0.1\n"},
      {ImportLayout::kFolder, "folder/times.txt", "0.0\n0.1\n0.2\n"}};
  const std::filesystem::path root = ScratchDir() / "import";
  if (!std::filesystem::exists(root / "folder" / "times.txt")) {
    std::vector<std::uint8_t> png;
    cv::imencode(".png", cv::Mat(4, 4, CV_8UC1, cv::Scalar(128)), png);
    const std::string_view bytes(reinterpret_cast<const char*>(png.data()), png.size());
    for (const char* dir : {"kitti/image_0", "tum/rgb", "folder/images"}) {
      std::filesystem::create_directories(root / dir);
      for (const char* image : {"0.png", "1.png", "2.png"}) WriteFile(root / dir / image, bytes);
    }
    for (const File& f : kFiles) WriteFile(root / f.name, f.valid);
  }
  const File& replaced = kFiles[static_cast<unsigned char>(input[0]) % 6];
  WriteFile(root / replaced.name, input.substr(1));
  ImportOptions options;
  std::filesystem::path source = root / "tum";
  if (replaced.layout == ImportLayout::kKitti) {
    source = root / "kitti";
    options.poses = source / "poses.txt";
  } else if (replaced.layout == ImportLayout::kFolder) {
    source = root / "folder" / "images";
    options.poses = root / "folder" / "poses.csv";
    options.times = root / "folder" / "times.txt";
  }
  std::filesystem::remove_all(root / "out");
  try {
    ImportDataset(replaced.layout, source, root / "out", options);
    ReadDataset(root / "out");
  } catch (const FileError&) {
  }
  WriteFile(root / replaced.name, replaced.valid);
}

// A camera image (the whole input), through the PNG and JPEG decoders and
// OpenCV's for other formats.
inline void Image(std::string_view input) {
  const std::filesystem::path path = ScratchDir() / "image";
  WriteFile(path, input);
  try {
    ReadImage(path);
  } catch (const FileError&) {
  }
}

// Sweep configurations (YAML, JSON) and sweep CSVs, by the first byte.
inline void Sweep(std::string_view input) {
  if (input.empty()) return;
  const int kind = static_cast<unsigned char>(input[0]) % 3;
  constexpr const char* kNames[] = {"sweep.yaml", "sweep.json", "runs.csv"};
  const std::filesystem::path path = ScratchDir() / kNames[kind];
  WriteFile(path, input.substr(1));
  try {
    if (kind == 2) {
      ReadSweepCsv(path);
    } else {
      ReadSweepConfigFile(path);
    }
  } catch (const FileError&) {
  }
}

// A vocabulary file (the whole input).
inline void VocabularyFile(std::string_view input) {
  const std::filesystem::path path = ScratchDir() / "vocabulary.yml";
  WriteFile(path, input);
  try {
    Vocabulary::Load(path);
  } catch (const FileError&) {
  }
}

}  // namespace catgraph::fuzz

#endif  // CATGRAPH_FUZZ_FUZZ_INPUTS_H_
