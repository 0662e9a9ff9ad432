#include "backend/io/image_file.h"

#include <cctype>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

// jpeglib.h needs FILE and size_t declared first (cstdio above).
#include <jpeglib.h>
#include <jerror.h>
#include <png.h>

#include <opencv2/imgcodecs.hpp>

#include "backend/io/file_error.h"
#include "backend/io/internal/text_line.h"

namespace catgraph {
namespace {

constexpr std::uintmax_t kMaxImageBytes = std::uintmax_t{256} << 20;
constexpr std::uint64_t kMaxImagePixels = std::uint64_t{1} << 26;  // 67 megapixels
constexpr std::string_view kPngSignature = "\x89PNG\r\n\x1a\n";

bool IsJpeg(const std::string& b) {
  return b.size() >= 2 && static_cast<unsigned char>(b[0]) == 0xFF && static_cast<unsigned char>(b[1]) == 0xD8;
}

std::uint32_t LittleEndian(const std::string& b, std::size_t at, int bytes) {
  std::uint32_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(b[at + static_cast<std::size_t>(i)]);
  return v;
}

// "P1" to "P6" and a blank, as the format (and OpenCV's decoder) requires:
// without the blank OpenCV would try its other decoders, DICOM among them,
// which asserts on a malformed file.
bool IsPnm(const std::string& b) {
  return b.size() >= 3 && b[0] == 'P' && b[1] >= '1' && b[1] <= '6' && std::isspace(static_cast<unsigned char>(b[2]));
}
bool IsBmp(const std::string& b) { return b.starts_with("BM"); }

// Width and height a PNM (PBM, PGM, PPM) or BMP header declares, read
// before OpenCV decodes the file; nullopt for a header that does not say.
std::optional<std::pair<std::uint64_t, std::uint64_t>> DeclaredSize(const std::string& b) {
  if (IsPnm(b)) {
    // "P6", then width and height as decimal tokens among blanks and
    // #-comments.
    std::uint64_t size[2] = {0, 0};
    std::size_t at = 2;
    for (std::uint64_t& v : size) {
      while (at < b.size() && (std::isspace(static_cast<unsigned char>(b[at])) || b[at] == '#')) {
        if (b[at] == '#') {
          while (at < b.size() && b[at] != '\n') ++at;
        } else {
          ++at;
        }
      }
      const std::size_t start = at;
      // At most 9 digits, so that width x height cannot overflow.
      while (at < b.size() && at - start < 9 && std::isdigit(static_cast<unsigned char>(b[at]))) {
        v = 10 * v + static_cast<std::uint64_t>(b[at++] - '0');
      }
      if (at == start) return std::nullopt;
    }
    return std::pair{size[0], size[1]};
  }
  if (IsBmp(b) && b.size() >= 26) {
    if (LittleEndian(b, 14, 4) == 12) {  // OS/2 core header: 16-bit sizes
      return std::pair{std::uint64_t{LittleEndian(b, 18, 2)}, std::uint64_t{LittleEndian(b, 20, 2)}};
    }
    // Signed 32-bit; a negative height is a top-down image.
    auto magnitude = [](std::uint32_t v) {
      const std::int64_t signed_v = static_cast<std::int32_t>(v);
      return static_cast<std::uint64_t>(signed_v < 0 ? -signed_v : signed_v);
    };
    return std::pair{magnitude(LittleEndian(b, 18, 4)), magnitude(LittleEndian(b, 22, 4))};
  }
  return std::nullopt;
}

// An image of more pixels than a camera frame has, refused before its pixels
// are allocated. Each side is below 2^32, so the product cannot overflow.
bool TooManyPixels(std::uint64_t width, std::uint64_t height) { return width * height > kMaxImagePixels; }

FileError TooManyPixelsError(const std::string& name, std::uint64_t width, std::uint64_t height) {
  return FileError(name, 0, "declares " + std::to_string(width) + " x " + std::to_string(height) +
                                " pixels; expected at most " + std::to_string(kMaxImagePixels) + " (a camera frame)");
}

// A PNG or JPEG cut short (a copy or download that did not finish), said so
// in plain words before the decoder reports it in its own.
std::optional<std::string> TruncationOf(const std::string& b) {
  if (b.starts_with(kPngSignature)) {
    const std::size_t end = b.rfind("IEND");
    if (end == std::string::npos || end + 8 > b.size()) return "a PNG without its end (IEND) chunk";
  } else if (IsJpeg(b)) {
    if (b.rfind("\xff\xd9") == std::string::npos) return "a JPEG without its end-of-image marker";
  }
  return std::nullopt;
}

// The decoders report errors by longjmp. Each function that sets a jump
// point below holds only trivially destructible locals, so the jump skips no
// destructor; C++ objects live in the callers.

struct PngSource {
  const std::string* bytes = nullptr;
  std::size_t at = 0;
  char message[200] = {};  // the first error or warning
};

void CopyMessage(char (&to)[200], const char* from) { std::snprintf(to, sizeof to, "%s", from); }

void PngReadBytes(png_structp png, png_bytep out, png_size_t n) {
  auto* source = static_cast<PngSource*>(png_get_io_ptr(png));
  if (n > source->bytes->size() - source->at) png_error(png, "the file ends inside a chunk");
  std::memcpy(out, source->bytes->data() + source->at, n);
  source->at += n;
}

[[noreturn]] void PngError(png_structp png, png_const_charp message) {
  CopyMessage(static_cast<PngSource*>(png_get_error_ptr(png))->message, message);
  png_longjmp(png, 1);
}

// A warning is kept for the error message should decoding fail without a
// message of its own; an image that decodes despite one (an unusual colour
// profile, a damaged ancillary chunk) is read.
void PngWarning(png_structp png, png_const_charp message) {
  auto* source = static_cast<PngSource*>(png_get_error_ptr(png));
  if (source->message[0] == '\0') CopyMessage(source->message, message);
}

bool PngReadHeader(png_structp png, png_infop info) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_read_info(png, info);
  return true;
}

// The transformations OpenCV's PNG reader applies for IMREAD_COLOR: 8 bits,
// alpha dropped, palette and grey expanded to three channels, BGR order.
bool PngReadPixels(png_structp png, png_infop info, png_bytepp rows) {
  if (setjmp(png_jmpbuf(png))) return false;
  const int colour = png_get_color_type(png, info);
  png_set_strip_16(png);
  png_set_strip_alpha(png);
  if (colour == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if ((colour & PNG_COLOR_MASK_COLOR) == 0) {
    if (png_get_bit_depth(png, info) < 8) png_set_expand_gray_1_2_4_to_8(png);
    png_set_gray_to_rgb(png);
  }
  png_set_bgr(png);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  if (png_get_channels(png, info) != 3 || png_get_bit_depth(png, info) != 8) {
    png_error(png, "an unsupported pixel layout");
  }
  png_read_image(png, rows);
  png_read_end(png, nullptr);
  return true;
}

cv::Mat DecodePng(const std::string& bytes, const std::string& name) {
  PngSource source{&bytes, 0, {}};
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &source, PngError, PngWarning);
  if (png == nullptr) throw FileError(name, 0, "cannot start the PNG decoder");
  png_infop info = png_create_info_struct(png);
  png_set_read_fn(png, &source, PngReadBytes);
  cv::Mat image;
  std::vector<png_bytep> rows;
  bool ok = info != nullptr && PngReadHeader(png, info);
  if (ok) {
    const std::uint64_t width = png_get_image_width(png, info), height = png_get_image_height(png, info);
    if (TooManyPixels(width, height)) {
      png_destroy_read_struct(&png, &info, nullptr);
      throw TooManyPixelsError(name, width, height);
    }
    image.create(static_cast<int>(height), static_cast<int>(width), CV_8UC3);
    for (int r = 0; r < image.rows; ++r) rows.push_back(image.ptr<png_byte>(r));
    ok = PngReadPixels(png, info, rows.data());
  }
  png_destroy_read_struct(&png, info != nullptr ? &info : nullptr, nullptr);
  if (!ok) throw FileError(name, 0, std::string("is a corrupt PNG (") + source.message + "); expected a whole image");
  return image;
}

struct JpegErrors {
  jpeg_error_mgr manager;  // first: libjpeg hands back a pointer to it
  std::jmp_buf jump;
  int damage = 0;          // warnings that the pixels were patched over
  char message[200] = {};
};

[[noreturn]] void JpegErrorExit(j_common_ptr jpeg) {
  auto* errors = reinterpret_cast<JpegErrors*>(jpeg->err);
  char text[JMSG_LENGTH_MAX];
  (*jpeg->err->format_message)(jpeg, text);
  CopyMessage(errors->message, text);
  std::longjmp(errors->jump, 1);
}

// libjpeg reports what it patched over (corrupt data, a premature end) as
// warnings, and would print them; here they are counted and the first kept.
// Junk bytes after the image data (JWRN_EXTRANEOUS_DATA, common in webcam
// JPEGs) leave the pixels whole and are not counted; trace messages are
// dropped.
void JpegEmitMessage(j_common_ptr jpeg, int level) {
  auto* errors = reinterpret_cast<JpegErrors*>(jpeg->err);
  if (level >= 0 || jpeg->err->msg_code == JWRN_EXTRANEOUS_DATA) return;
  if (errors->damage++ == 0) {
    char text[JMSG_LENGTH_MAX];
    (*jpeg->err->format_message)(jpeg, text);
    CopyMessage(errors->message, text);
  }
}

bool JpegReadHeader(jpeg_decompress_struct* jpeg, JpegErrors* errors, const std::string& bytes) {
  if (setjmp(errors->jump)) return false;
  jpeg_create_decompress(jpeg);
  jpeg_mem_src(jpeg, reinterpret_cast<const unsigned char*>(bytes.data()), static_cast<unsigned long>(bytes.size()));
  jpeg_read_header(jpeg, TRUE);
  return true;
}

// OpenCV's JPEG reader for IMREAD_COLOR: libjpeg-turbo's BGR output, grey
// expanded; the decoder's default DCT and upsampling.
bool JpegReadPixels(jpeg_decompress_struct* jpeg, JpegErrors* errors, JSAMPARRAY rows, JDIMENSION height) {
  if (setjmp(errors->jump)) return false;
  jpeg->out_color_space = JCS_EXT_BGR;
  jpeg_start_decompress(jpeg);
  while (jpeg->output_scanline < height) jpeg_read_scanlines(jpeg, rows + jpeg->output_scanline, 1);
  jpeg_finish_decompress(jpeg);
  return true;
}

std::optional<cv::Mat> DecodeJpeg(const std::string& bytes, const std::string& name) {
  jpeg_decompress_struct jpeg{};
  JpegErrors errors{};
  jpeg.err = jpeg_std_error(&errors.manager);
  errors.manager.error_exit = JpegErrorExit;
  errors.manager.emit_message = JpegEmitMessage;
  cv::Mat image;
  std::vector<JSAMPROW> rows;
  bool ok = JpegReadHeader(&jpeg, &errors, bytes);
  if (ok && TooManyPixels(jpeg.image_width, jpeg.image_height)) {
    const FileError error = TooManyPixelsError(name, jpeg.image_width, jpeg.image_height);
    jpeg_destroy_decompress(&jpeg);
    throw error;
  }
  // CMYK and YCCK (print workflows, not cameras) are left to OpenCV, which
  // converts them itself.
  const bool cmyk = ok && (jpeg.jpeg_color_space == JCS_CMYK || jpeg.jpeg_color_space == JCS_YCCK);
  if (ok && !cmyk) {
    image.create(static_cast<int>(jpeg.image_height), static_cast<int>(jpeg.image_width), CV_8UC3);
    for (int r = 0; r < image.rows; ++r) rows.push_back(image.ptr<JSAMPLE>(r));
    ok = JpegReadPixels(&jpeg, &errors, rows.data(), jpeg.image_height);
  }
  jpeg_destroy_decompress(&jpeg);
  if (!ok || errors.damage > 0) {
    throw FileError(name, 0, std::string("is a corrupt JPEG (") + errors.message + "); expected a whole image");
  }
  if (cmyk) return std::nullopt;
  return image;
}

}  // namespace

cv::Mat ReadImage(const std::filesystem::path& path) {
  const std::string name = path.string();
  const std::string bytes = ReadWholeFile(path, kMaxImageBytes, "an image (PNG, JPEG, ...)");
  if (const auto truncated = TruncationOf(bytes)) {
    throw FileError(name, 0, "is " + *truncated + " (cut short?); expected a whole image");
  }
  if (bytes.starts_with(kPngSignature)) return DecodePng(bytes, name);
  if (IsJpeg(bytes)) {
    if (auto image = DecodeJpeg(bytes, name)) return std::move(*image);
  } else if (const auto size = DeclaredSize(bytes)) {
    if (TooManyPixels(size->first, size->second)) throw TooManyPixelsError(name, size->first, size->second);
  } else {
    // OpenCV's other decoders (TIFF, WebP, JPEG 2000, ...) would allocate
    // whatever their header declares, up to 2^30 pixels, unchecked here.
    throw FileError(name, 0, "is not an image catgraph reads; expected PNG, JPEG, PNM (PGM, PPM) or BMP");
  }
  cv::Mat image;
  try {
    image = cv::imdecode(cv::Mat(1, static_cast<int>(bytes.size()), CV_8U, const_cast<char*>(bytes.data())),
                         cv::IMREAD_COLOR);
  } catch (const cv::Exception& e) {
    throw FileError(name, 0, "cannot decode the image: " + e.msg);
  }
  if (image.empty()) throw FileError(name, 0, "cannot decode the image; expected a whole PNG, JPEG, PNM (PGM, PPM) or BMP file");
  return image;
}

}  // namespace catgraph
