// An output folder that appears whole or not at all, and never costs the user
// a file catgraph did not write.
//
// A command writes into a hidden staging folder beside the target
// (".NAME.catgraph-tmp-PID-N") and Commit() puts it in place: a fresh target
// by one rename; a target that holds only an earlier output of the same
// command (its manifest, ".catgraph-output", lists every file it wrote) by an
// atomic exchange of the two folders (renameat2 RENAME_EXCHANGE), after which
// the old output is removed. A run that is killed or fails leaves the old
// output whole; its staging folder is removed at once or, after SIGKILL, by
// the next run to the same target.
//
// A target that exists and holds anything else (a file the manifest does not
// list, another command's output, the user's data) is refused when the
// OutputDirectory is made, before any work, unless `overwrite` is set: then
// the new files are moved in one by one over files of the same name and
// nothing else in the folder is touched.
#ifndef CATGRAPH_BACKEND_IO_OUTPUT_DIRECTORY_H_
#define CATGRAPH_BACKEND_IO_OUTPUT_DIRECTORY_H_

#include <filesystem>
#include <string>
#include <vector>

namespace catgraph {

// The manifest's file name inside an output folder.
inline constexpr const char* kOutputManifestName = ".catgraph-output";

class OutputDirectory {
 public:
  // `command` names the writer in the manifest ("map", "simulate", ...).
  // `inputs` are the files and folders the run reads: the target may neither
  // be one of them nor hold one. Throws FileError naming the target when it
  // cannot be used.
  OutputDirectory(std::filesystem::path target, std::string command, bool overwrite,
                  const std::vector<std::filesystem::path>& inputs = {});
  ~OutputDirectory();
  OutputDirectory(const OutputDirectory&) = delete;
  OutputDirectory& operator=(const OutputDirectory&) = delete;

  // Where the command writes its files.
  const std::filesystem::path& path() const { return staging_; }
  const std::filesystem::path& target() const { return target_; }

  // Writes the manifest and puts the staged folder in place of the target.
  // Throws FileError when the target changed since construction so that it
  // may no longer be replaced, or a rename fails; the target is then as it
  // was.
  void Commit();

 private:
  std::filesystem::path target_;    // as the user named it, for messages
  std::filesystem::path resolved_;  // absolute, no trailing separator
  std::filesystem::path staging_;
  std::string command_;
  bool overwrite_ = false;
  bool committed_ = false;
};

// Throws FileError naming `output` when it is one of `inputs` (the same file
// through any path, link or hard link) or a folder that holds one of them.
void RefuseOutputOverInput(const std::filesystem::path& output,
                           const std::vector<std::filesystem::path>& inputs);

// The same for every output of a run (empty paths are skipped), and no two
// outputs the same file.
void RefuseOutputClashes(const std::vector<std::filesystem::path>& outputs,
                         const std::vector<std::filesystem::path>& inputs);

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_IO_OUTPUT_DIRECTORY_H_
