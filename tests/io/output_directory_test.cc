// Output folders appear whole or not at all, replace only catgraph's own
// earlier output of the same command, and never touch a file catgraph did not
// write; no output may be an input of its run.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tests/catch.h"

#include "backend/io/file_error.h"
#include "backend/io/output_directory.h"
#include "tests/test_support.h"

namespace catgraph {
namespace {

namespace fs = std::filesystem;

void Write(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream(path) << text;
}

std::vector<std::string> Listing(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    if (!entry.is_directory()) names.push_back(entry.path().lexically_relative(dir).generic_string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

// The message of the FileError `make` throws ("" when it throws none).
template <typename F>
std::string ErrorOf(F&& make) {
  try {
    make();
  } catch (const FileError& e) {
    return e.what();
  }
  return "";
}

TEST_CASE("an output folder appears only on commit, with a manifest of its files", "[io][output]") {
  const fs::path root = testing::TempDir("output_fresh");
  const fs::path target = root / "out";
  {
    OutputDirectory out(target, "map", false);
    Write(out.path() / "report.json", "{}\n");
    Write(out.path() / "images" / "a.png", "png");
    CHECK_FALSE(fs::exists(target));
    CHECK(out.path().parent_path() == fs::absolute(root).lexically_normal());
    out.Commit();
  }
  CHECK(Listing(target) == std::vector<std::string>{".catgraph-output", "images/a.png", "report.json"});
  const std::string manifest = testing::ReadText(target / kOutputManifestName);
  CHECK(manifest.find("\"command\": \"map\"") != std::string::npos);
  CHECK(manifest.find("images/a.png") != std::string::npos);
  // A run that fails before its commit leaves nothing behind.
  {
    OutputDirectory failed(root / "other", "map", false);
    Write(failed.path() / "x.csv", "1\n");
  }
  CHECK_FALSE(fs::exists(root / "other"));
  CHECK(std::distance(fs::directory_iterator(root), fs::directory_iterator()) == 1);
  fs::remove_all(root);
}

TEST_CASE("an earlier output of the same command is replaced whole; until the commit it is untouched",
          "[io][output]") {
  const fs::path root = testing::TempDir("output_replace");
  const fs::path target = root / "out";
  {
    OutputDirectory first(target, "simulate", false);
    Write(first.path() / "images" / "000000.png", "old0");
    Write(first.path() / "images" / "000001.png", "old1");
    Write(first.path() / "frames.csv", "old\n");
    first.Commit();
  }
  {
    OutputDirectory second(target, "simulate", false);
    Write(second.path() / "images" / "000000.png", "new0");
    Write(second.path() / "frames.csv", "new\n");
    CHECK(testing::ReadText(target / "frames.csv") == "old\n");
    CHECK(fs::exists(target / "images" / "000001.png"));
    second.Commit();
  }
  CHECK(Listing(target) == std::vector<std::string>{".catgraph-output", "frames.csv", "images/000000.png"});
  CHECK(testing::ReadText(target / "images" / "000000.png") == "new0");
  CHECK(Listing(root).size() == 3);  // no staging folder left
  {
    OutputDirectory failed(target, "simulate", false);
    Write(failed.path() / "frames.csv", "half\n");
  }
  CHECK(testing::ReadText(target / "frames.csv") == "new\n");
  fs::remove_all(root);
}

TEST_CASE("a folder with the user's files is refused by name; --overwrite writes beside them and deletes nothing",
          "[io][output]") {
  const fs::path root = testing::TempDir("output_foreign");
  const fs::path user = root / "U";
  Write(user / "images" / "000000.png", "mine0");
  Write(user / "images" / "000499.png", "mine499");
  Write(user / "notes.txt", "mine\n");
  const std::string refused = ErrorOf([&] { OutputDirectory out(user, "simulate", false); });
  CHECK(refused.find(user.string() + ": holds files catgraph did not write") == 0);
  CHECK(refused.find("--overwrite") != std::string::npos);
  {
    OutputDirectory out(user, "simulate", true);
    Write(out.path() / "images" / "000000.png", "ours0");
    Write(out.path() / "frames.csv", "ours\n");
    out.Commit();
  }
  CHECK(testing::ReadText(user / "images" / "000000.png") == "ours0");  // same name: replaced
  CHECK(testing::ReadText(user / "images" / "000499.png") == "mine499");
  CHECK(testing::ReadText(user / "notes.txt") == "mine\n");
  CHECK(Listing(root).size() == 5);  // U's four files and the manifest, no staging folder
  // Still not all catgraph's: refused again without --overwrite.
  CHECK_FALSE(ErrorOf([&] { OutputDirectory out(user, "simulate", false); }).empty());

  // A file the user added to an earlier output, another command's output, a
  // plain file and a symbolic link are refused too.
  const fs::path own = root / "own";
  {
    OutputDirectory out(own, "map", false);
    Write(out.path() / "report.json", "{}\n");
    out.Commit();
  }
  Write(own / "my-notes.md", "keep\n");
  CHECK(ErrorOf([&] { OutputDirectory out(own, "map", false); }).find("my-notes.md") != std::string::npos);
  fs::remove(own / "my-notes.md");
  CHECK(ErrorOf([&] { OutputDirectory out(own, "localize", false); })
            .find("holds the output of 'catgraph map', not of localize") != std::string::npos);
  Write(root / "file", "x\n");
  CHECK(ErrorOf([&] { OutputDirectory out(root / "file", "map", false); }).find("is not a folder") !=
        std::string::npos);
  CHECK(ErrorOf([&] { OutputDirectory out(root / "file", "map", true); }).find("is not a folder") !=
        std::string::npos);
  fs::create_directory_symlink(own, root / "link");
  CHECK(ErrorOf([&] { OutputDirectory out(root / "link", "map", false); }).find("symbolic link") !=
        std::string::npos);
  CHECK(testing::ReadText(own / "report.json") == "{}\n");
  fs::remove_all(root);
}

TEST_CASE("an output that is an input, or holds one, is refused; two outputs may not share a file",
          "[io][output]") {
  const fs::path root = testing::TempDir("output_input");
  Write(root / "data" / "frames.csv", "x\n");
  Write(root / "g.g2o", "VERTEX_SE2 0 0 0 0\n");
  fs::create_hard_link(root / "g.g2o", root / "hard.g2o");
  fs::create_symlink(root / "g.g2o", root / "soft.g2o");
  CHECK(ErrorOf([&] { RefuseOutputOverInput(root / "g.g2o", {root / "." / "g.g2o"}); })
            .find("is also an input of this run") != std::string::npos);
  CHECK_FALSE(ErrorOf([&] { RefuseOutputOverInput(root / "hard.g2o", {root / "g.g2o"}); }).empty());
  CHECK_FALSE(ErrorOf([&] { RefuseOutputOverInput(root / "soft.g2o", {root / "g.g2o"}); }).empty());
  CHECK(ErrorOf([&] { RefuseOutputOverInput(root, {root / "data" / "frames.csv"}); })
            .find("holds an input of this run") != std::string::npos);
  CHECK(ErrorOf([&] { RefuseOutputOverInput(root / "data" / "out.png", {root / "data" / "frames.csv"}); }).empty());
  CHECK(ErrorOf([&] { RefuseOutputOverInput(root / "data2", {root / "data"}); }).empty());  // a prefix, not a parent
  CHECK(ErrorOf([&] { RefuseOutputClashes({root / "a.g2o", root / "./a.g2o"}, {}); })
            .find("is named for two outputs") != std::string::npos);
  CHECK(ErrorOf([&] { RefuseOutputClashes({root / "a.g2o", "", root / "b.g2o"}, {""}); }).empty());
  CHECK_FALSE(ErrorOf([&] { OutputDirectory out(root / "data", "localize", true, {root / "data"}); }).empty());
  CHECK(testing::ReadText(root / "data" / "frames.csv") == "x\n");
  fs::remove_all(root);
}

TEST_CASE("the staging folder of a run that died is removed by the next run to the same target", "[io][output]") {
  const fs::path root = testing::TempDir("output_abandoned");
  // A process id that is certainly not running: a child that has exited and
  // been waited for.
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  REQUIRE(child > 0);
  ::waitpid(child, nullptr, 0);
  const fs::path dead = root / (".out.catgraph-tmp-" + std::to_string(child) + "-0");
  const fs::path alive = root / (".out.catgraph-tmp-" + std::to_string(::getppid()) + "-0");
  Write(dead / "half.csv", "1\n");
  Write(alive / "half.csv", "1\n");
  {
    OutputDirectory out(root / "out", "map", false);
    CHECK_FALSE(fs::exists(dead));
    CHECK(fs::exists(alive));  // another run's, still going
    out.Commit();
  }
  fs::remove_all(root);
}

}  // namespace
}  // namespace catgraph
