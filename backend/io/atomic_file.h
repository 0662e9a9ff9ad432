// Writing a file so that readers never see it half-written.
//
// The content goes to a temporary file in the same directory, is flushed and
// synced, and is then renamed over the final name, which POSIX makes atomic.
// If the writer throws or the stream fails, the temporary file is removed and
// the final name keeps whatever it held before.
#ifndef CATGRAPH_BACKEND_IO_ATOMIC_FILE_H_
#define CATGRAPH_BACKEND_IO_ATOMIC_FILE_H_

#include <filesystem>
#include <cstdint>
#include <functional>
#include <ostream>
#include <string_view>
#include <vector>

namespace catgraph {

// Throws FileError when the file cannot be created, written or renamed.
void WriteFileAtomically(const std::filesystem::path& path,
                         const std::function<void(std::ostream&)>& write);

// The same for bytes already in memory (an encoded image).
void WriteBytesAtomically(const std::filesystem::path& path, const std::vector<std::uint8_t>& bytes);

// Creates `dir` and its parents; throws FileError naming it ("cannot create
// the <what>: <reason>") when that fails.
void CreateDirectories(const std::filesystem::path& dir, std::string_view what = "directory");

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_IO_ATOMIC_FILE_H_
