#include "backend/io/output_directory.h"

#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <set>
#include <string>
#include <system_error>

#include <nlohmann/json.hpp>

#include "backend/io/atomic_file.h"
#include "backend/io/file_error.h"

namespace catgraph {
namespace {

namespace fs = std::filesystem;

constexpr const char* kStagingTag = ".catgraph-tmp-";

// What Commit() will do with the target.
enum class TargetState { kAbsent, kReplaceable, kForeign };

struct Classification {
  TargetState state = TargetState::kAbsent;
  std::string reason;  // kForeign: why, for the error message
};

// Every file below `dir` (not directories), relative to it, sorted.
std::vector<std::string> FilesBelow(const fs::path& dir) {
  std::vector<std::string> files;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != fs::recursive_directory_iterator();
       it.increment(ec)) {
    if (it->is_directory(ec) && !it->is_symlink(ec)) continue;
    files.push_back(it->path().lexically_relative(dir).generic_string());
  }
  if (ec) throw FileError(dir.string(), 0, "cannot list the folder: " + ec.message());
  std::sort(files.begin(), files.end());
  return files;
}

// The command and files an earlier catgraph output recorded, or nothing when
// the manifest is missing or unreadable.
std::optional<std::pair<std::string, std::set<std::string>>> ReadManifest(const fs::path& dir) {
  std::ifstream in(dir / kOutputManifestName);
  if (!in) return std::nullopt;
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (!j.is_object() || !j.contains("command") || !j["command"].is_string() || !j.contains("files") ||
      !j["files"].is_array()) {
    return std::nullopt;
  }
  std::set<std::string> files;
  for (const auto& f : j["files"]) {
    if (!f.is_string()) return std::nullopt;
    files.insert(f.get<std::string>());
  }
  return std::make_pair(j["command"].get<std::string>(), std::move(files));
}

Classification Classify(const fs::path& target, const std::string& command) {
  std::error_code ec;
  const fs::file_status link = fs::symlink_status(target, ec);
  if (ec || link.type() == fs::file_type::not_found) return {TargetState::kAbsent, {}};
  if (link.type() == fs::file_type::symlink) return {TargetState::kForeign, "is a symbolic link"};
  if (link.type() != fs::file_type::directory) {
    return {TargetState::kForeign, "exists and is not a folder"};
  }
  const std::vector<std::string> present = FilesBelow(target);
  if (present.empty()) return {TargetState::kReplaceable, {}};
  const auto manifest = ReadManifest(target);
  if (!manifest) {
    return {TargetState::kForeign, "holds files catgraph did not write (" + (target / present.front()).string() + ")"};
  }
  if (manifest->first != command) {
    return {TargetState::kForeign, "holds the output of 'catgraph " + manifest->first + "', not of " + command};
  }
  for (const std::string& f : present) {
    if (f != kOutputManifestName && !manifest->second.contains(f)) {
      return {TargetState::kForeign, "holds a file catgraph did not write (" + (target / f).string() + ")"};
    }
  }
  return {TargetState::kReplaceable, {}};
}

[[noreturn]] void ThrowForeign(const fs::path& target, const std::string& reason) {
  throw FileError(target.string(), 0,
                  reason + "; choose another output folder, or pass --overwrite to write into it (files of the "
                           "same name are replaced, nothing else is touched)");
}

// The staging folders of runs that died before committing, e.g. to SIGKILL.
void RemoveAbandonedStaging(const fs::path& parent, const std::string& prefix) {
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(parent, ec)) {
    const std::string name = entry.path().filename().string();
    if (!name.starts_with(prefix)) continue;
    const std::string rest = name.substr(prefix.size());
    const auto dash = rest.find('-');
    if (dash == std::string::npos || dash == 0) continue;
    pid_t pid = 0;
    try {
      pid = static_cast<pid_t>(std::stol(rest.substr(0, dash)));
    } catch (const std::exception&) {
      continue;
    }
    if (pid <= 0 || pid == ::getpid()) continue;
    if (::kill(pid, 0) == 0 || errno != ESRCH) continue;  // still running
    std::error_code ignored;
    fs::remove_all(entry.path(), ignored);
  }
}

void Rename(const fs::path& from, const fs::path& to, unsigned flags, const fs::path& named) {
  if (::renameat2(AT_FDCWD, from.c_str(), AT_FDCWD, to.c_str(), flags) != 0) {
    throw FileError(named.string(), 0, std::string("cannot move the output into place: ") + std::strerror(errno));
  }
}

// Component by component: is `inner` `outer` or below it?
bool IsSameOrBelow(const fs::path& inner, const fs::path& outer) {
  auto i = inner.begin();
  for (auto o = outer.begin(); o != outer.end(); ++o, ++i) {
    if (o->empty()) continue;  // a trailing separator
    if (i == inner.end() || *i != *o) return false;
  }
  return true;
}

}  // namespace

void RefuseOutputOverInput(const fs::path& output, const std::vector<fs::path>& inputs) {
  std::error_code ec;
  const fs::path out = fs::weakly_canonical(fs::absolute(output), ec);
  for (const fs::path& input : inputs) {
    std::error_code e1, e2;
    const bool same = fs::exists(output, e1) && fs::exists(input, e2) && fs::equivalent(output, input, e1);
    const fs::path in = fs::weakly_canonical(fs::absolute(input), e2);
    if (same || (!ec && !e2 && IsSameOrBelow(in, out))) {
      throw FileError(output.string(), 0,
                      same || in == out ? "is also an input of this run (" + input.string() + "); write elsewhere"
                                        : "holds an input of this run (" + input.string() + "); write elsewhere");
    }
  }
}

void RefuseOutputClashes(const std::vector<fs::path>& outputs, const std::vector<fs::path>& inputs) {
  std::vector<fs::path> given_inputs, written;
  for (const fs::path& p : inputs) {
    if (!p.empty()) given_inputs.push_back(p);
  }
  for (const fs::path& output : outputs) {
    if (output.empty()) continue;
    RefuseOutputOverInput(output, given_inputs);
    std::error_code ec;
    const fs::path canonical = fs::weakly_canonical(fs::absolute(output), ec);
    for (const fs::path& other : written) {
      if (canonical == other) throw FileError(output.string(), 0, "is named for two outputs of this run");
    }
    written.push_back(canonical);
  }
}

OutputDirectory::OutputDirectory(fs::path target, std::string command, bool overwrite,
                                 const std::vector<fs::path>& inputs)
    : target_(std::move(target)), command_(std::move(command)), overwrite_(overwrite) {
  RefuseOutputOverInput(target_, inputs);
  const Classification c = Classify(target_, command_);
  if (c.state == TargetState::kForeign && !overwrite_) ThrowForeign(target_, c.reason);
  if (c.state == TargetState::kForeign && fs::exists(target_) && !fs::is_directory(target_)) {
    throw FileError(target_.string(), 0, "exists and is not a folder; expected an output folder");
  }
  fs::path absolute = fs::absolute(target_).lexically_normal();
  if (!absolute.has_filename()) absolute = absolute.parent_path();  // "out/" -> "out"
  const fs::path parent = absolute.parent_path();
  CreateDirectories(parent, "output folder's parent");
  std::string prefix = ".";  // built by appending: GCC 12 warns falsely (-Wrestrict) on "." + name + tag
  prefix += absolute.filename().string();
  prefix += kStagingTag;
  RemoveAbandonedStaging(parent, prefix);
  static std::atomic<unsigned> counter{0};
  staging_ = parent / (prefix + std::to_string(::getpid()) + "-" + std::to_string(counter++));
  std::error_code ec;
  fs::remove_all(staging_, ec);
  CreateDirectories(staging_, "staging folder");
  resolved_ = parent / absolute.filename();
}

OutputDirectory::~OutputDirectory() {
  if (committed_) return;
  std::error_code ignored;
  fs::remove_all(staging_, ignored);
}

void OutputDirectory::Commit() {
  const std::vector<std::string> files = FilesBelow(staging_);
  WriteFileAtomically(staging_ / kOutputManifestName, [&](std::ostream& out) {
    out << nlohmann::json{{"command", command_}, {"files", files}}.dump(1) << '\n';
  });
  const Classification c = Classify(resolved_, command_);
  std::error_code ec;
  switch (c.state) {
    case TargetState::kAbsent:
      Rename(staging_, resolved_, RENAME_NOREPLACE, target_);
      break;
    case TargetState::kReplaceable:
      // One atomic step: readers see the old folder or the new one.
      Rename(staging_, resolved_, RENAME_EXCHANGE, target_);
      fs::remove_all(staging_, ec);  // now the old output
      break;
    case TargetState::kForeign:
      if (!overwrite_) ThrowForeign(target_, c.reason);
      for (const std::string& f : files) {
        const fs::path to = resolved_ / f;
        CreateDirectories(to.parent_path(), "output folder");
        Rename(staging_ / f, to, 0, to);
      }
      Rename(staging_ / kOutputManifestName, resolved_ / kOutputManifestName, 0, target_);
      fs::remove_all(staging_, ec);
      break;
  }
  committed_ = true;
}

}  // namespace catgraph
