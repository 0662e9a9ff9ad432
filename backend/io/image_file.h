// Camera images from files a stranger wrote.
//
// PNG and JPEG are decoded here with libpng and libjpeg, whose complaints
// become the error instead of lines on stderr: a corrupt image (a bad
// checksum, a broken compressed stream, a JPEG the decoder had to patch up)
// is refused naming the file and what is wrong, where OpenCV's reader prints
// the library's message and, for JPEG, returns the patched pixels. PNM
// (PBM, PGM, PPM) and BMP go to OpenCV once their header's size is checked;
// other formats are refused, as OpenCV's readers for them would allocate
// whatever size a header declares. The pixels are those OpenCV's
// cv::imread(path, cv::IMREAD_COLOR) gives.
#ifndef CATGRAPH_BACKEND_IO_IMAGE_FILE_H_
#define CATGRAPH_BACKEND_IO_IMAGE_FILE_H_

#include <cstdint>
#include <filesystem>

#include <opencv2/core.hpp>

namespace catgraph {

// An image file as 8-bit colour (BGR). Throws FileError naming the file when
// it cannot be read or decoded, is corrupt, is of another format, is larger
// than 256 MB, or declares more than 2^26 pixels (checked before any pixel is
// allocated).
cv::Mat ReadImage(const std::filesystem::path& path);

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_IO_IMAGE_FILE_H_
