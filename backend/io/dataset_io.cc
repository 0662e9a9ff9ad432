#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "backend/io/atomic_file.h"
#include "backend/io/dataset.h"
#include "backend/io/file_error.h"
#include "backend/io/internal/text_line.h"
#include "backend/io/json_integer.h"

namespace catgraph {
namespace {

constexpr std::size_t kMaxCsvLineBytes = 4096;
constexpr std::uintmax_t kMaxMetaBytes = 256u << 20;  // meta.json holds per-frame flags

// Calls `row` for every data line of a CSV file whose header starts with
// `columns`; extra columns named in `optional` may follow. With `comments`,
// lines starting with '#' are skipped as blank ones are.
template <typename RowFn>
void ReadCsv(const std::filesystem::path& path, const std::vector<std::string>& columns,
             const std::vector<std::string>& optional, bool comments, RowFn row) {
  std::string expected_header;
  for (const auto& c : columns) expected_header += (expected_header.empty() ? "" : ",") + c;
  for (const auto& c : optional) expected_header += "[," + c + "]";
  std::ifstream in = OpenForReading(path, "a CSV table with header '" + expected_header + "'");
  const std::string name = path.string();
  std::string text;
  int number = 0;
  bool header = true;
  std::size_t width = columns.size();
  while (ReadBoundedLine(in, text, kMaxCsvLineBytes, name, number, "a CSV row")) {
    ++number;
    if (!text.empty() && text.back() == '\r') text.pop_back();
    const std::size_t first = text.find_first_not_of(kWhitespace);
    if (first == std::string::npos || (comments && text[first] == '#')) continue;
    const std::vector<std::string_view> fields = SplitCsv(text);
    if (header) {
      header = false;
      // On a mismatch only the first wrong column is quoted (shortened), not
      // the line: the file may be anything.
      std::string found;
      for (std::size_t i = 0; found.empty() && i < fields.size(); ++i) {
        const bool known = i < columns.size() + optional.size();
        if (!known || fields[i] != (i < columns.size() ? columns[i] : optional[i - columns.size()])) {
          const std::string_view token = fields[i].substr(0, 64);
          found = "column " + std::to_string(i + 1) + " is '" + std::string(token) +
                  (token.size() < fields[i].size() ? "...'" : "'");
        }
      }
      if (found.empty() && fields.size() < columns.size()) {
        found = "found " + std::to_string(fields.size()) + " of its " + std::to_string(columns.size()) + " columns";
      }
      if (!found.empty()) {
        throw FileError(name, number, "expected the header '" + expected_header + "'; " + found);
      }
      width = fields.size();
      continue;
    }
    if (fields.size() != width) {
      throw FileError(name, number,
                      "expected " + std::to_string(width) + " comma-separated fields, found " +
                          std::to_string(fields.size()));
    }
    row(Line(name, number, fields, "row"));
  }
  if (header) throw FileError(name, 0, "is empty; expected a header line and rows");
}

}  // namespace

std::vector<TimedPose2> ReadPoseTable(const std::filesystem::path& path, bool comments) {
  std::vector<TimedPose2> poses;
  ReadCsv(path, {"timestamp", "x", "y", "theta"}, {}, comments, [&](const Line& line) {
    TimedPose2 p;
    p.timestamp_s = line.Number(0, "timestamp");
    p.pose = Pose2(line.Number(1, "x"), line.Number(2, "y"), line.Number(3, "theta"));
    if (!poses.empty() && !(p.timestamp_s > poses.back().timestamp_s)) {
      line.Fail("timestamp " + std::string(line.token(0)) +
                " is not after the previous row's; expected strictly increasing timestamps");
    }
    poses.push_back(p);
  });
  if (poses.size() < 2) {
    throw FileError(path.string(), 0,
                    "holds " + std::to_string(poses.size()) + " rows; expected at least 2 poses");
  }
  return poses;
}

namespace {

// Whether `path`, every symbolic link followed, lies inside `root` (itself
// canonical): a dataset reads nothing outside its folder.
bool ResolvesInside(const std::filesystem::path& root, const std::filesystem::path& path) {
  std::error_code ec;
  const std::filesystem::path resolved = std::filesystem::weakly_canonical(path, ec);
  if (ec) return false;
  auto r = root.begin();
  for (auto p = resolved.begin(); r != root.end(); ++r, ++p) {
    if (p == resolved.end() || *p != *r) return false;
  }
  return true;
}

std::vector<DatasetFrame> ReadFrames(const std::filesystem::path& root) {
  const std::filesystem::path path = root / "frames.csv";
  std::error_code canonical_error;
  const std::filesystem::path canonical_root = std::filesystem::canonical(root, canonical_error);
  std::vector<DatasetFrame> frames;
  ReadCsv(path, {"timestamp", "image", "traversal", "changed"}, {"changed_fraction"}, /*comments=*/false,
          [&](const Line& line) {
            DatasetFrame f;
            f.timestamp_s = line.Number(0, "timestamp");
            if (!frames.empty() && !(f.timestamp_s > frames.back().timestamp_s)) {
              line.Fail("timestamp " + std::string(line.token(0)) +
                        " is not after the previous frame's; expected strictly increasing "
                        "timestamps");
            }
            f.image = std::string(line.token(1));
            const std::filesystem::path image(f.image);
            if (f.image.empty() || image.is_absolute() ||
                std::find(image.begin(), image.end(), "..") != image.end()) {
              line.Fail("image '" + f.image +
                        "': expected a path relative to the dataset folder, inside it");
            }
            std::error_code ec;
            const std::filesystem::file_status status = std::filesystem::status(root / image, ec);
            if (!std::filesystem::exists(status)) {
              line.Fail("image '" + f.image + "' does not exist (expected " +
                        (root / image).string() + ")");
            }
            if (!std::filesystem::is_regular_file(status)) {
              line.Fail("image '" + f.image + "' is not a regular file (a folder, FIFO or device)");
            }
            if (!ResolvesInside(canonical_root, root / image)) {
              line.Fail("image '" + f.image + "' is a symbolic link (or lies below one) that leads out of the "
                        "dataset folder; expected every file inside it");
            }
            const double traversal = line.Number(2, "traversal");
            if (traversal < 1 || traversal > 1e6 || traversal != std::floor(traversal)) {
              line.Fail("traversal '" + std::string(line.token(2)) +
                        "': expected a positive integer");
            }
            f.traversal = static_cast<int>(traversal);
            const std::string_view changed = line.token(3);
            if (changed != "0" && changed != "1") {
              line.Fail("changed '" + std::string(changed) + "': expected 0 or 1");
            }
            f.changed = changed == "1";
            if (line.size() > 4) {
              f.changed_fraction = line.Number(4, "changed_fraction");
              if (f.changed_fraction < 0.0 || f.changed_fraction > 1.0) {
                line.Fail("changed_fraction " + std::string(line.token(4)) +
                          ": expected a number in [0, 1]");
              }
            }
            frames.push_back(std::move(f));
          });
  if (frames.empty()) throw FileError(path.string(), 0, "holds no frames; expected at least one");
  return frames;
}

// A furniture item's traversals: small positive integers.
std::vector<int> Traversals(const nlohmann::json& j) {
  std::vector<int> out;
  for (const auto& t : j) out.push_back(static_cast<int>(IntegerIn(t, "traversals", 1, 1'000'000)));
  return out;
}

Polygon2 PolygonFromJson(const nlohmann::json& j) {
  Polygon2 polygon;
  for (const auto& p : j) polygon.emplace_back(p.at(0).get<double>(), p.at(1).get<double>());
  if (polygon.size() < 3) throw std::invalid_argument("a polygon needs at least 3 points");
  return polygon;
}

nlohmann::json PolygonToJson(const Polygon2& polygon) {
  nlohmann::json j = nlohmann::json::array();
  for (const auto& p : polygon) j.push_back({p.x(), p.y()});
  return j;
}

DatasetMeta ReadMeta(const std::filesystem::path& path) {
  const std::string name = path.string();
  const std::string text = ReadWholeFile(path, kMaxMetaBytes, "meta.json (the dataset's description)");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    // nlohmann reports the 1-based byte offset of the error.
    throw FileError(name, LineOfOffset(text, e.byte > 0 ? e.byte - 1 : 0),
                    std::string("expected valid JSON: ") + e.what());
  } catch (const nlohmann::json::exception& e) {  // a number out of range (found by fuzzing)
    throw FileError(name, 0, std::string("expected valid JSON: ") + e.what());
  }
  DatasetMeta meta;
  try {
    if (!j.is_object()) throw std::invalid_argument("expected a JSON object at the top level");
    meta.format_version = static_cast<int>(IntegerIn(j.at("format_version"), "format_version", 0, 1'000'000));
    if (meta.format_version < 1 || meta.format_version > kDatasetFormatVersion) {
      throw std::invalid_argument("format_version " + std::to_string(meta.format_version) +
                                  " is not supported; expected 1.." +
                                  std::to_string(kDatasetFormatVersion));
    }
    meta.scenario = j.value("scenario", "");
    meta.seed = static_cast<std::uint64_t>(IntegerIn(j, "seed", 0, 0, std::numeric_limits<std::int64_t>::max()));
    meta.synthetic_images = j.value("synthetic_images", false);
    meta.synthetic_odometry = j.value("synthetic_odometry", false);
    meta.synthetic_ground_truth = j.value("synthetic_ground_truth", false);
    meta.note = j.value("note", "");
    meta.odometry_rate_hz = j.value("odometry_rate_hz", 0.0);
    if (j.contains("camera")) {
      const auto& c = j.at("camera");
      meta.camera.model = c.value("model", "unknown");
      meta.camera.width_px = static_cast<int>(IntegerIn(c, "width_px", 0, 0, 1 << 20));
      meta.camera.height_px = static_cast<int>(IntegerIn(c, "height_px", 0, 0, 1 << 20));
      meta.camera.hfov_deg = c.value("hfov_deg", 0.0);
      meta.camera.vfov_deg = c.value("vfov_deg", 0.0);
      meta.camera.height_m = c.value("height_m", 0.0);
      meta.camera.frame_rate_hz = c.value("frame_rate_hz", 0.0);
    }
    for (const auto& r : j.value("changed_regions", nlohmann::json::array())) {
      meta.changed_regions.push_back(
          {r.at("name").get<std::string>(), r.value("kind", ""), PolygonFromJson(r.at("polygon"))});
    }
    for (const auto& f : j.at("frame_changed")) meta.frame_changed.push_back(IntegerIn(f, "frame_changed", 0, 1) != 0);
    if (j.contains("floor_plan")) {
      const auto& plan = j.at("floor_plan");
      for (const auto& w : plan.value("walls", nlohmann::json::array())) {
        meta.walls.emplace_back(w.at(0).get<double>(), w.at(1).get<double>(),
                                w.at(2).get<double>(), w.at(3).get<double>());
      }
      for (const auto& f : plan.value("furniture", nlohmann::json::array())) {
        meta.furniture.push_back({f.at("name").get<std::string>(), PolygonFromJson(f.at("polygon")),
                                  f.value("height_m", 0.0),
                                  Traversals(f.at("traversals"))});
      }
    }
  } catch (const nlohmann::json::exception& e) {
    throw FileError(name, 0, std::string("expected the meta.json keys of docs/dataset-format.md: ") +
                                 e.what());
  } catch (const std::invalid_argument& e) {
    throw FileError(name, 0, e.what());
  }
  return meta;
}

// The consistency checks shared by the reader and the writer; `fail(file,
// line, message)` reports the first problem.
template <typename FailFn>
void CheckConsistency(const Dataset& d, FailFn fail) {
  if (d.meta.frame_changed.size() != d.frames.size()) {
    fail("meta.json", 0,
         "frame_changed has " + std::to_string(d.meta.frame_changed.size()) +
             " entries; expected one per frame of frames.csv (" + std::to_string(d.frames.size()) +
             ")");
  }
  for (std::size_t i = 0; i < d.frames.size(); ++i) {
    if (d.meta.frame_changed[i] != d.frames[i].changed) {
      fail("meta.json", 0,
           "frame_changed[" + std::to_string(i) + "] disagrees with frames.csv row " +
               std::to_string(i + 2) + " (changed " + (d.frames[i].changed ? "1" : "0") + ")");
    }
  }
  // Every frame has odometry and, when there is ground truth, a true pose:
  // both are interpolated at the frame times.
  auto check_covers = [&](const std::vector<TimedPose2>& poses, const char* file, const char* what) {
    const double t0 = poses.front().timestamp_s, t1 = poses.back().timestamp_s;
    for (std::size_t i = 0; i < d.frames.size(); ++i) {
      const double t = d.frames[i].timestamp_s;
      if (t < t0 || t > t1) {
        char range[96];
        std::snprintf(range, sizeof range, "[%.6f, %.6f]", t0, t1);
        fail("frames.csv", static_cast<int>(i) + 2,
             "frame timestamp " + std::to_string(t) + " lies outside the time range " + range + " of " + file +
                 "; expected every frame to have " + what);
      }
    }
  };
  check_covers(d.odometry, "odometry.csv", "odometry");
  if (d.HasGroundTruth()) check_covers(d.ground_truth, "groundtruth.csv", "a ground-truth pose");
}

void WriteCsv(const std::filesystem::path& path, const std::string& header,
              const std::function<void(std::ostream&)>& rows) {
  WriteFileAtomically(path, [&](std::ostream& out) {
    out << header << '\n';
    rows(out);
  });
}

void WritePoses(const std::filesystem::path& path, const std::vector<TimedPose2>& poses) {
  WriteCsv(path, "timestamp,x,y,theta", [&](std::ostream& out) {
    char line[160];
    for (const auto& p : poses) {
      std::snprintf(line, sizeof line, "%.6f,%.6f,%.6f,%.9f\n", p.timestamp_s, p.pose.x(),
                    p.pose.y(), p.pose.theta());
      out << line;
    }
  });
}

}  // namespace

std::vector<int> Dataset::Traversals() const {
  std::vector<int> ids;
  for (const auto& f : frames) {
    if (std::find(ids.begin(), ids.end(), f.traversal) == ids.end()) ids.push_back(f.traversal);
  }
  return ids;
}

Dataset ReadDataset(const std::filesystem::path& root) {
  std::error_code ec;
  if (!std::filesystem::is_directory(root, ec)) {
    throw FileError(root.string(), 0,
                    std::filesystem::exists(root, ec)
                        ? "is not a directory; expected a dataset folder (docs/dataset-format.md)"
                        : "no such directory; expected a dataset folder (docs/dataset-format.md)");
  }
  const std::filesystem::path canonical_root = std::filesystem::canonical(root, ec);
  for (const char* table : {"frames.csv", "odometry.csv", "groundtruth.csv", "meta.json"}) {
    if (std::filesystem::exists(std::filesystem::symlink_status(root / table, ec)) &&
        !ResolvesInside(canonical_root, root / table)) {
      throw FileError((root / table).string(), 0,
                      "is a symbolic link that leads out of the dataset folder; expected every file inside it");
    }
  }
  Dataset d;
  d.root = root;
  d.meta = ReadMeta(root / "meta.json");
  d.frames = ReadFrames(root);
  d.odometry = ReadPoseTable(root / "odometry.csv");
  if (std::filesystem::exists(root / "groundtruth.csv", ec)) {
    d.ground_truth = ReadPoseTable(root / "groundtruth.csv");
  }
  CheckConsistency(d, [&](const std::string& file, int line, const std::string& message) {
    throw FileError((root / file).string(), line, message);
  });
  return d;
}

std::vector<std::filesystem::path> DatasetFiles(const Dataset& d) {
  std::vector<std::filesystem::path> files = {d.root / "frames.csv", d.root / "odometry.csv", d.root / "meta.json"};
  if (d.HasGroundTruth()) files.push_back(d.root / "groundtruth.csv");
  for (std::size_t i = 0; i < d.frames.size(); ++i) files.push_back(d.ImagePath(i));
  return files;
}

void WriteDatasetTables(const Dataset& d) {
  if (d.odometry.size() < 2) throw std::invalid_argument("a dataset needs at least 2 odometry poses");
  CheckConsistency(d, [](const std::string& file, int line, const std::string& message) {
    throw std::invalid_argument(file + (line > 0 ? ":" + std::to_string(line) : "") + ": " +
                                message);
  });
  std::filesystem::create_directories(d.root);
  WriteCsv(d.root / "frames.csv", "timestamp,image,traversal,changed,changed_fraction",
           [&](std::ostream& out) {
             char line[64];
             for (const auto& f : d.frames) {
               std::snprintf(line, sizeof line, "%.6f,", f.timestamp_s);
               out << line << f.image << ',' << f.traversal << ',' << (f.changed ? 1 : 0);
               std::snprintf(line, sizeof line, ",%.4f\n", f.changed_fraction);
               out << line;
             }
           });
  WritePoses(d.root / "odometry.csv", d.odometry);
  if (d.HasGroundTruth()) WritePoses(d.root / "groundtruth.csv", d.ground_truth);

  const DatasetMeta& m = d.meta;
  nlohmann::ordered_json j;
  j["format_version"] = kDatasetFormatVersion;
  j["scenario"] = m.scenario;
  j["seed"] = m.seed;
  j["synthetic_images"] = m.synthetic_images;
  j["synthetic_odometry"] = m.synthetic_odometry;
  j["synthetic_ground_truth"] = m.synthetic_ground_truth;
  j["note"] = m.note;
  j["camera"] = {{"model", m.camera.model},       {"width_px", m.camera.width_px},
                 {"height_px", m.camera.height_px}, {"hfov_deg", m.camera.hfov_deg},
                 {"vfov_deg", m.camera.vfov_deg},   {"height_m", m.camera.height_m},
                 {"frame_rate_hz", m.camera.frame_rate_hz}};
  j["odometry_rate_hz"] = m.odometry_rate_hz;
  j["frames"] = d.frames.size();
  j["traversals"] = d.Traversals();
  nlohmann::ordered_json regions = nlohmann::ordered_json::array();
  for (const auto& r : m.changed_regions) {
    regions.push_back({{"name", r.name}, {"kind", r.kind}, {"polygon", PolygonToJson(r.polygon)}});
  }
  j["changed_regions"] = regions;
  std::vector<int> flags;
  for (bool f : m.frame_changed) flags.push_back(f ? 1 : 0);
  j["frame_changed"] = flags;
  if (!m.walls.empty() || !m.furniture.empty()) {
    nlohmann::ordered_json walls = nlohmann::ordered_json::array();
    for (const auto& w : m.walls) walls.push_back({w[0], w[1], w[2], w[3]});
    nlohmann::ordered_json furniture = nlohmann::ordered_json::array();
    for (const auto& f : m.furniture) {
      furniture.push_back({{"name", f.name},
                           {"height_m", f.height_m},
                           {"traversals", f.traversals},
                           {"polygon", PolygonToJson(f.polygon)}});
    }
    j["floor_plan"] = {{"walls", walls}, {"furniture", furniture}};
  }
  WriteFileAtomically(d.root / "meta.json", [&](std::ostream& out) { out << j.dump(1) << '\n'; });
}

Pose2 InterpolatePose(const std::vector<TimedPose2>& poses, double t) {
  if (poses.empty() || t < poses.front().timestamp_s || t > poses.back().timestamp_s) {
    throw std::out_of_range("time " + std::to_string(t) + " outside the poses' time range");
  }
  const auto after = std::lower_bound(
      poses.begin(), poses.end(), t,
      [](const TimedPose2& p, double time) { return p.timestamp_s < time; });
  if (after == poses.begin()) return after->pose;
  const auto before = after - 1;
  const double span = after->timestamp_s - before->timestamp_s;
  return Interpolate(before->pose, after->pose, (t - before->timestamp_s) / span);
}

std::vector<Pose2> PosesAtFrames(const Dataset& dataset, const std::vector<TimedPose2>& poses) {
  std::vector<Pose2> at_frames;
  if (poses.empty()) return at_frames;
  at_frames.reserve(dataset.frames.size());
  for (const DatasetFrame& f : dataset.frames) at_frames.push_back(InterpolatePose(poses, f.timestamp_s));
  return at_frames;
}

bool PointInPolygon(const Polygon2& polygon, const Eigen::Vector2d& p) {
  bool inside = false;
  for (std::size_t i = 0, j = polygon.size() - 1; i < polygon.size(); j = i++) {
    const Eigen::Vector2d& a = polygon[i];
    const Eigen::Vector2d& b = polygon[j];
    if ((a.y() > p.y()) != (b.y() > p.y()) &&
        p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x()) {
      inside = !inside;
    }
  }
  return inside;
}

}  // namespace catgraph
