// Files that declare absurd sizes get a clear error, not an out-of-memory
// kill: an image header claiming 100 000 x 100 000 pixels, a 100 MB line, a
// pose id of 2^41, an oversized configuration. docs/fuzzing.md.
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tests/catch.h"
#include <opencv2/imgcodecs.hpp>

#include "experiments/sweep.h"
#include "backend/io/dataset.h"
#include "backend/io/file_error.h"
#include "backend/io/graph_io.h"
#include "frontend/vocabulary.h"
#include "simulation/scenario.h"
#include "tests/test_support.h"

namespace catgraph {
namespace {

std::string BigEndian32(std::uint32_t v) {
  return {static_cast<char>(v >> 24), static_cast<char>(v >> 16), static_cast<char>(v >> 8), static_cast<char>(v)};
}

// The CRC-32 a PNG chunk ends with (ISO 3309, as zlib's crc32).
std::uint32_t Crc32(const std::string& bytes) {
  std::uint32_t crc = 0xFFFFFFFFu;
  for (const char c : bytes) {
    crc ^= static_cast<unsigned char>(c);
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

std::string PngChunk(const std::string& type, const std::string& data) {
  return BigEndian32(static_cast<std::uint32_t>(data.size())) + type + data + BigEndian32(Crc32(type + data));
}

std::string LittleEndian(std::uint32_t v, int bytes) {
  std::string out;
  for (int k = 0; k < bytes; ++k) out += static_cast<char>(v >> (8 * k));
  return out;
}

TEST_CASE("an image declaring 100 000 x 100 000 pixels is refused before its pixels are allocated",
          "[io][bad-input][bounds]") {
  const auto dir = testing::TempDir("bounds_image");
  // PNG: a well-formed file (checksums right, IDAT and IEND present) whose header
  // declares the size.
  std::ofstream(dir / "huge.png", std::ios::binary)
      << std::string("\x89PNG\r\n\x1a\n", 8)
      << PngChunk("IHDR", BigEndian32(100000) + BigEndian32(100000) + std::string("\x08\x02\x00\x00\x00", 5))
      << PngChunk("IDAT", "") << PngChunk("IEND", "");
  CHECK_THROWS_WITH(ReadImage(dir / "huge.png"), Catch::Contains("huge.png: declares 100000 x 100000 pixels"));
  // JPEG: start of image, an APP0 segment, a baseline start of frame with
  // height 60 000 and width 50 000, a start of scan, end of image.
  std::ofstream(dir / "huge.jpg", std::ios::binary)
      << std::string("\xFF\xD8\xFF\xE0\x00\x04\x00\x00\xFF\xC0\x00\x11\x08", 13) << std::string("\xEA\x60", 2)
      << std::string("\xC3\x50", 2) << std::string("\x03\x01\x22\x00\x02\x11\x01\x03\x11\x01", 10)
      << std::string("\xFF\xDA\x00\x0C\x03\x01\x00\x02\x11\x03\x11\x00\x3F\x00\xFF\xD9", 16);
  CHECK_THROWS_WITH(ReadImage(dir / "huge.jpg"), Catch::Contains("huge.jpg: declares 50000 x 60000 pixels"));
  // PGM and BMP (read by OpenCV once the size is checked).
  std::ofstream(dir / "huge.pgm", std::ios::binary) << "P5\n# a comment\n100000 100000\n255\n" << std::string(16, '\0');
  CHECK_THROWS_WITH(ReadImage(dir / "huge.pgm"), Catch::Contains("huge.pgm: declares 100000 x 100000 pixels"));
  std::ofstream(dir / "huge.bmp", std::ios::binary)
      << "BM" << LittleEndian(70, 4) << LittleEndian(0, 4) << LittleEndian(54, 4) << LittleEndian(40, 4)
      << LittleEndian(100000, 4) << LittleEndian(static_cast<std::uint32_t>(-100000), 4) << LittleEndian(1, 2)
      << LittleEndian(24, 2) << std::string(40, '\0');
  CHECK_THROWS_WITH(ReadImage(dir / "huge.bmp"), Catch::Contains("huge.bmp: declares 100000 x 100000 pixels"));
  // A format whose size is not checked here (TIFF) is refused by name.
  std::ofstream(dir / "frame.tif", std::ios::binary) << std::string("II*\0\x08\0\0\0", 8) << std::string(32, '\0');
  CHECK_THROWS_WITH(ReadImage(dir / "frame.tif"),
                    Catch::Contains("frame.tif: is not an image catgraph reads; expected PNG, JPEG, PNM"));
  // A header that is fine but a file cut short: refused before the decoder
  // (which would print its own line to stderr) sees it.
  std::ofstream(dir / "cut.png", std::ios::binary)
      << std::string("\x89PNG\r\n\x1a\n", 8) << BigEndian32(13) << "IHDR" << BigEndian32(10) << BigEndian32(10);
  CHECK_THROWS_WITH(ReadImage(dir / "cut.png"), Catch::Contains("cut.png: is a PNG without its end (IEND) chunk"));
  std::vector<std::uint8_t> png, jpeg;
  const cv::Mat3b picture(40, 60, cv::Vec3b(10, 200, 30));
  cv::imencode(".png", picture, png);
  cv::imencode(".jpg", picture, jpeg);
  std::ofstream(dir / "half.png", std::ios::binary).write(reinterpret_cast<const char*>(png.data()), png.size() / 2);
  std::ofstream(dir / "half.jpg", std::ios::binary).write(reinterpret_cast<const char*>(jpeg.data()), jpeg.size() / 2);
  std::ofstream(dir / "whole.jpg", std::ios::binary).write(reinterpret_cast<const char*>(jpeg.data()), jpeg.size());
  CHECK_THROWS_WITH(ReadImage(dir / "half.png"), Catch::Contains("half.png: is a PNG without its end"));
  CHECK_THROWS_WITH(ReadImage(dir / "half.jpg"), Catch::Contains("half.jpg: is a JPEG without its end-of-image marker"));
  CHECK(ReadImage(dir / "whole.jpg").size() == cv::Size(60, 40));
  std::filesystem::remove_all(dir);
}

TEST_CASE("a 100 MB line in a dataset table is refused naming the line", "[io][bad-input][bounds]") {
  const auto dir = testing::TempDir("bounds_line");
  std::ofstream(dir / "meta.json") << R"({"format_version": 1, "frame_changed": [0]})";
  {
    std::ofstream f(dir / "frames.csv");
    f << "timestamp,image,traversal,changed,changed_fraction\n0.0,images/";
    const std::string chunk(1 << 20, 'a');
    for (int i = 0; i < 100; ++i) f << chunk;
    f << ".png,1,0,0.0\n";
  }
  CHECK_THROWS_WITH(ReadDataset(dir), Catch::Contains("frames.csv:2:") && Catch::Contains("longer than"));
  std::filesystem::remove_all(dir);
}

TEST_CASE("pose ids are sparse up to 2^40 and refused beyond", "[io][bad-input][bounds]") {
  std::istringstream billion("VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1000000000 1 0 0\nEDGE_SE2 0 1000000000 1 0 0 1 0 0 1 0 1\n");
  const GraphFile file = ReadGraph(billion, "billion.g2o");
  CHECK(std::get<PoseGraph2>(file.graph).vertices.size() == 2);
  std::istringstream beyond("VERTEX_SE2 2199023255552 0 0 0\n");  // 2^41
  CHECK_THROWS_WITH(ReadGraph(beyond, "beyond.g2o"), Catch::Contains("beyond.g2o:1:"));
}

TEST_CASE("a sweep configuration larger than 1 MB is refused", "[io][bad-input][bounds]") {
  const auto dir = testing::TempDir("bounds_sweep");
  std::ofstream(dir / "sweep.yaml") << "# " << std::string(2 << 20, 'x') << "\noutput: runs.csv\n";
  CHECK_THROWS_WITH(ReadSweepConfigFile(dir / "sweep.yaml"), Catch::Contains("expected at most 1048576"));
  std::filesystem::remove_all(dir);
}

// "Billion laughs": nine levels of ten aliases stand for 10^9 strings in a
// few hundred bytes. Refused at the first alias, before any expansion, in
// every YAML catgraph reads.
TEST_CASE("YAML aliases are refused before they are expanded", "[io][bad-input][bounds]") {
  const auto dir = testing::TempDir("bounds_yaml");
  std::ostringstream text;  // (a stream: GCC 12 warns falsely on string sums here)
  text << "a0: &a0 [x, x, x, x, x, x, x, x, x, x]\n";
  for (int level = 1; level < 10; ++level) {
    text << 'a' << level << ": &a" << level << " [*a" << level - 1;
    for (int k = 1; k < 10; ++k) text << ", *a" << level - 1;
    text << "]\n";
  }
  const std::string bomb = text.str();
  std::ofstream(dir / "sweep.yaml") << "output: runs.csv\n" << bomb;
  CHECK_THROWS_WITH(ReadSweepConfigFile(dir / "sweep.yaml"),
                    Catch::Contains("sweep.yaml:3: a YAML alias (*name); expected plain values"));
  std::ofstream(dir / "scenario.yaml") << "name: bomb\n" << bomb;
  CHECK_THROWS_WITH(LoadScenario((dir / "scenario.yaml").string()), Catch::Contains("scenario.yaml:3: a YAML alias"));
  std::ofstream(dir / "vocabulary.yml") << "format_version: 1\n" << bomb;
  CHECK_THROWS_WITH(Vocabulary::Load(dir / "vocabulary.yml"), Catch::Contains("vocabulary.yml:3: a YAML alias"));
  std::filesystem::remove_all(dir);
}

// yaml-cpp's document loop does not advance past a stray token at document
// level; every YAML catgraph reads is one document, and the rest is refused
// at its line rather than looping.
TEST_CASE("YAML text after the first document is refused at its line", "[io][bad-input][bounds]") {
  const auto dir = testing::TempDir("bounds_yaml_documents");
  std::ofstream(dir / "sweep.yaml") << "output: runs.csv\n---\noutput: other.csv\n";
  CHECK_THROWS_WITH(ReadSweepConfigFile(dir / "sweep.yaml"),
                    Catch::Contains("sweep.yaml:2: text after the first YAML document; expected one document"));
  std::ofstream(dir / "stray.yaml") << ", 1\n";
  CHECK_THROWS_WITH(ReadSweepConfigFile(dir / "stray.yaml"), Catch::Contains("stray.yaml:1: text after the first"));
  std::ofstream(dir / "scenario.yaml") << "name: two\n...\n, x\n";
  CHECK_THROWS_WITH(LoadScenario((dir / "scenario.yaml").string()), Catch::Contains("scenario.yaml:3: text after"));
  std::ofstream(dir / "vocabulary.yml") << "%YAML:1.0\n---\nformat_version: 1\n---\n";
  CHECK_THROWS_WITH(Vocabulary::Load(dir / "vocabulary.yml"), Catch::Contains("vocabulary.yml:4: text after"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace catgraph
