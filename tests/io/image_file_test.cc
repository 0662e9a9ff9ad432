// Camera images: the pixels OpenCV's reader gives, and a corrupt file refused
// by name without a word from the decoders on stderr.
#include "backend/io/image_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "tests/catch.h"
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "tests/test_support.h"

namespace catgraph {
namespace {

// A picture with structure in every channel (gradients and a disc), so that
// a decoder that swaps channels or rows would show it.
cv::Mat3b Picture(int width, int height) {
  cv::Mat3b p(height, width);
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) {
      p(r, c) = cv::Vec3b(static_cast<std::uint8_t>(4 * c), static_cast<std::uint8_t>(3 * r),
                          static_cast<std::uint8_t>((r * c) % 251));
    }
  }
  cv::circle(p, {width / 2, height / 2}, height / 3, cv::Scalar(20, 220, 90), -1);
  return p;
}

void WriteBytes(const std::filesystem::path& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()),
                                              static_cast<std::streamsize>(bytes.size()));
}

bool SamePixels(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0.0;
}

// What the process writes to stderr while `f` runs.
template <typename F>
std::string StderrOf(F f) {
  const auto file = std::filesystem::temp_directory_path() / ("catgraph_stderr_" + std::to_string(::getpid()));
  std::fflush(stderr);
  const int saved = ::dup(2);
  const int out = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  ::dup2(out, 2);
  ::close(out);
  f();
  std::fflush(stderr);
  ::dup2(saved, 2);
  ::close(saved);
  const std::string text = testing::ReadText(file);
  std::filesystem::remove(file);
  return text;
}

TEST_CASE("ReadImage gives OpenCV's pixels for every PNG and JPEG layout a camera or tool writes", "[io][image]") {
  const auto dir = testing::TempDir("image_layouts");
  const cv::Mat3b colour = Picture(97, 61);
  cv::Mat grey, colour_alpha, colour16, grey16;
  cv::cvtColor(colour, grey, cv::COLOR_BGR2GRAY);
  cv::cvtColor(colour, colour_alpha, cv::COLOR_BGR2BGRA);
  colour.convertTo(colour16, CV_16UC3, 257.0);
  grey.convertTo(grey16, CV_16U, 251.0);
  struct Case {
    const char* name;
    cv::Mat image;
    std::vector<int> parameters;
  };
  const std::vector<Case> cases = {
      {"colour.png", colour, {}},
      {"grey.png", grey, {}},
      {"alpha.png", colour_alpha, {}},
      {"colour16.png", colour16, {}},
      {"grey16.png", grey16, {}},
      {"bilevel.png", grey > 100, {cv::IMWRITE_PNG_BILEVEL, 1}},
      {"colour.jpg", colour, {}},
      {"grey.jpg", grey, {}},
      {"progressive.jpg", colour, {cv::IMWRITE_JPEG_PROGRESSIVE, 1}},
  };
  for (const Case& c : cases) {
    CAPTURE(c.name);
    const auto path = dir / c.name;
    REQUIRE(cv::imwrite(path.string(), c.image, c.parameters));
    const cv::Mat expected = cv::imread(path.string(), cv::IMREAD_COLOR);
    cv::Mat read;
    CHECK(StderrOf([&] { read = ReadImage(path); }).empty());
    CHECK(read.type() == CV_8UC3);
    CHECK(SamePixels(read, expected));
  }
  // Junk between the image data and the end marker, as some webcams write:
  // the pixels are whole and the image is read.
  std::vector<std::uint8_t> jpeg;
  cv::imencode(".jpg", colour, jpeg);
  jpeg.insert(jpeg.end() - 2, {0x12, 0x34});
  WriteBytes(dir / "junk.jpg", jpeg);
  cv::Mat read;
  CHECK(StderrOf([&] { read = ReadImage(dir / "junk.jpg"); }).empty());
  CHECK(SamePixels(read, cv::imread((dir / "colour.jpg").string(), cv::IMREAD_COLOR)));
  std::filesystem::remove_all(dir);
}

TEST_CASE("PNM and BMP frames give OpenCV's pixels", "[io][image]") {
  const auto dir = testing::TempDir("image_pnm_bmp");
  const cv::Mat3b colour = Picture(90, 60);
  cv::Mat grey;
  cv::cvtColor(colour, grey, cv::COLOR_BGR2GRAY);
  for (const auto& [name, picture] : {std::pair<std::string, cv::Mat>{"frame.ppm", colour}, {"frame.pgm", grey},
                                      {"frame.bmp", colour}, {"grey.bmp", grey}}) {
    INFO(name);
    REQUIRE(cv::imwrite((dir / name).string(), picture));
    const cv::Mat read = ReadImage(dir / name);
    CHECK(SamePixels(read, cv::imread((dir / name).string(), cv::IMREAD_COLOR)));
    CHECK(read.size() == cv::Size(90, 60));
  }
  std::filesystem::remove_all(dir);
}

TEST_CASE("a corrupt PNG or JPEG is refused naming the file, and the decoders print nothing",
          "[io][image][bad-input]") {
  const auto dir = testing::TempDir("image_corrupt");
  const cv::Mat3b colour = Picture(120, 80);
  std::vector<std::uint8_t> png, jpeg;
  cv::imencode(".png", colour, png);
  cv::imencode(".jpg", colour, jpeg);

  // One byte of the compressed data changed: the stream no longer inflates
  // (and the chunk's checksum no longer matches).
  std::vector<std::uint8_t> bad_png = png;
  const std::string text(png.begin(), png.end());
  const std::size_t idat = text.find("IDAT");
  REQUIRE(idat != std::string::npos);
  bad_png[idat + 20] ^= 0x5A;
  WriteBytes(dir / "bad.png", bad_png);
  std::string err = StderrOf(
      [&] { CHECK_THROWS_WITH(ReadImage(dir / "bad.png"), Catch::Contains("bad.png: is a corrupt PNG (IDAT: ")); });
  CHECK(err.empty());

  // A stretch of the entropy-coded data overwritten, as a bad sector or a
  // dropped packet does: libjpeg would patch it over with a warning.
  std::vector<std::uint8_t> bad_jpeg = jpeg;
  for (std::size_t k = bad_jpeg.size() / 2; k < bad_jpeg.size() / 2 + 40; ++k) bad_jpeg[k] = 0xFF;
  WriteBytes(dir / "bad.jpg", bad_jpeg);
  err = StderrOf(
      [&] { CHECK_THROWS_WITH(ReadImage(dir / "bad.jpg"), Catch::Contains("bad.jpg: is a corrupt JPEG (")); });
  CHECK(err.empty());

  // Not an image at all, in a file named like one.
  std::ofstream(dir / "text.png") << "not an image\n";
  CHECK_THROWS_WITH(ReadImage(dir / "text.png"), Catch::Contains("text.png: is not an image catgraph reads"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace catgraph
