#include "backend/io/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <random>
#include <string>

#include "backend/io/file_error.h"

namespace catgraph {
namespace {

// Flushes file data to disk so that the rename cannot expose an empty file
// after a power loss.
void SyncFile(const std::filesystem::path& path) {
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

}  // namespace

void WriteFileAtomically(const std::filesystem::path& path,
                         const std::function<void(std::ostream&)>& write) {
  const std::string name = path.string();
  if (std::filesystem::is_directory(path)) {
    throw FileError(name, 0, "is a directory; expected a file name to write");
  }
  // The process id and a counter keep concurrent writers of the same final
  // name from sharing a temporary file.
  static std::atomic<unsigned> counter{0};
  std::filesystem::path tmp = path;
  tmp += ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++);
  try {
    {
      std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
      if (!out) {
        const int error = errno;
        const std::filesystem::path folder = path.parent_path().empty() ? "." : path.parent_path();
        if (!std::filesystem::is_directory(folder)) {
          throw FileError(name, 0, "cannot create file: its folder " + folder.string() + " does not exist");
        }
        throw FileError(name, 0, std::string("cannot create file: ") + std::strerror(error));
      }
      errno = 0;
      write(out);
      out.flush();
      if (!out) {
        // The stream keeps no error code; errno is the failed write's
        // (ENOSPC for a full disk, EFBIG past the file-size limit).
        const int error = errno;
        throw FileError(name, 0, std::string("write failed: ") + (error != 0 ? std::strerror(error) : "disk full?"));
      }
    }
    SyncFile(tmp);
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) throw FileError(name, 0, "cannot rename temporary file into place: " + ec.message());
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
    throw;
  }
}

void WriteBytesAtomically(const std::filesystem::path& path, const std::vector<std::uint8_t>& bytes) {
  WriteFileAtomically(path, [&](std::ostream& out) {
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  });
}

void CreateDirectories(const std::filesystem::path& dir, std::string_view what) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw FileError(dir.string(), 0, "cannot create the " + std::string(what) + ": " + ec.message());
}

}  // namespace catgraph
