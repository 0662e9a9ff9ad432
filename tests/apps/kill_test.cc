// Killed half-way with SIGKILL, catgraph leaves no torn file under a final
// name and no mix of old and new outputs (an output folder is staged and
// swapped into place whole, the sweep's CSV grows by whole lines), and a
// rerun completes; the sweep resumes without repeating the runs it had
// finished. docs/cli.md "Outputs".
#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <functional>
#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "tests/catch.h"

#include "experiments/sweep.h"
#include "backend/io/dataset.h"
#include "tests/test_support.h"

namespace catgraph {
namespace {

// Runs the catgraph binary with `args`, its output to `log`; when
// `kill_when` is given it is polled every 2 ms and, once true, the process is
// killed with SIGKILL unless it ended first. A `file_size_limit` (bytes) makes
// every write past it fail with EFBIG, as a full disk makes it fail with
// ENOSPC. Returns the exit status, or -1 when it was killed.
int RunProcess(const std::vector<std::string>& args, const std::function<bool()>& kill_when = {},
        const std::string& log = "/dev/null", rlim_t file_size_limit = RLIM_INFINITY) {
  std::vector<std::string> copy = args;
  std::string binary = CATGRAPH_BINARY;
  std::vector<char*> argv = {binary.data()};
  for (std::string& a : copy) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int out = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(out, 1);
    ::dup2(out, 2);
    if (file_size_limit != RLIM_INFINITY) {
      ::signal(SIGXFSZ, SIG_IGN);  // a write past the limit then fails instead of killing (kept across exec)
      const rlimit limit{file_size_limit, file_size_limit};
      ::setrlimit(RLIMIT_FSIZE, &limit);
    }
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  REQUIRE(pid > 0);
  int status = 0;
  if (kill_when) {
    while (!kill_when()) {
      if (::waitpid(pid, &status, WNOHANG) == pid) return WIFEXITED(status) ? WEXITSTATUS(status) : -2;
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    ::kill(pid, SIGKILL);
    ::waitpid(pid, &status, 0);
    return -1;
  }
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -2;
}

// True once `seconds` have passed since it was made.
std::function<bool()> After(double seconds) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  return [deadline] { return std::chrono::steady_clock::now() >= deadline; };
}

std::string Slurp(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Every file under a final name (temporary files carry ".tmp.") is whole:
// images decode, JSON parses, other text ends with its last newline.
// Returns how many files it checked.
int CheckNoTornFile(const std::filesystem::path& dir) {
  int checked = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir)) {
    if (!entry.is_regular_file()) continue;
    const std::filesystem::path& p = entry.path();
    if (p.filename().string().find(".tmp.") != std::string::npos) continue;
    INFO(p);
    const std::string ext = p.extension().string();
    if (ext == ".png") {
      CHECK_FALSE(cv::imread(p.string(), cv::IMREAD_UNCHANGED).empty());
    } else {
      const std::string text = Slurp(p);
      if (ext == ".json") {
        CHECK_NOTHROW(nlohmann::json::parse(text));
      } else {
        REQUIRE_FALSE(text.empty());
        CHECK(text.back() == '\n');
      }
    }
    ++checked;
  }
  return checked;
}

// Kill times drawn in [lo, hi] seconds by a fixed seed, shortest first.
std::vector<double> KillTimes(int n, double lo, double hi, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<double> t;
  for (int i = 0; i < n; ++i) t.push_back(std::uniform_real_distribution<double>(lo, hi)(rng));
  std::sort(t.begin(), t.end());
  return t;
}

// The names in `dir`, hidden ones included, sorted.
std::vector<std::string> Listing(const std::filesystem::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) names.push_back(entry.path().filename());
  std::sort(names.begin(), names.end());
  return names;
}

TEST_CASE("simulate and map killed at random points leave the earlier output whole and a rerun replaces it",
          "[apps][kill][slow]") {
  const auto root = testing::TempDir("kill_simulate_map");
  const std::string data = (root / "data").string(), map = (root / "map").string();
  auto simulate = [&](const char* frames) {
    return std::vector<std::string>{"simulate", "--scenario", "office-change", "--frames", frames,
                                    "-o",       data,           "--threads",     "1",      "--quiet"};
  };
  REQUIRE(RunProcess(simulate("100")) == 0);
  const std::string old_frames = Slurp(std::filesystem::path(data) / "frames.csv");
  int killed = 0;
  // The killed runs are asked for 3000 frames, which take several seconds on
  // one thread, so that a kill at up to 1.5 s always comes before the end
  // (400 frames were done in 1.4 s on a quiet machine).
  for (const double t : KillTimes(4, 0.05, 1.5, 11)) {
    CAPTURE(t);
    killed += RunProcess(simulate("3000"), After(t)) == -1;
    CheckNoTornFile(data);
    CHECK(Slurp(std::filesystem::path(data) / "frames.csv") == old_frames);  // the old dataset, whole
    CHECK(ReadDataset(data).frames.size() == 100);
  }
  CHECK(killed > 0);
  REQUIRE(RunProcess(simulate("400")) == 0);
  CHECK(CheckNoTornFile(data) > 400);  // the images, the tables and the manifest
  CHECK(ReadDataset(data).frames.size() == 400);
  CHECK(Listing(root) == std::vector<std::string>{"data"});  // the killed runs' staging folders are gone

  const std::vector<std::string> mapping = {"map", data, "-o", map, "--quiet", "--threads", "1"};
  const std::filesystem::path report = std::filesystem::path(map) / "report.json";
  killed = 0;
  for (const double t : KillTimes(4, 0.2, 4.0, 12)) {
    CAPTURE(t);
    killed += RunProcess(mapping, After(t)) == -1;
    CHECK_FALSE(std::filesystem::exists(map));  // all or nothing
  }
  CHECK(killed > 0);
  REQUIRE(RunProcess(mapping) == 0);
  const std::string first = Slurp(report);
  CHECK(nlohmann::json::parse(first).at("frames") == 400);
  killed = 0;
  for (const double t : KillTimes(2, 0.2, 4.0, 13)) {
    CAPTURE(t);
    killed += RunProcess(mapping, After(t)) == -1;
    CheckNoTornFile(map);
    CHECK(Slurp(report) == first);
  }
  CHECK(killed > 0);
  REQUIRE(RunProcess(mapping) == 0);
  CheckNoTornFile(map);
  CHECK(Listing(root) == std::vector<std::string>{"data", "map"});
  std::filesystem::remove_all(root);
}

// A full disk cannot be had in the suite (no tmpfs to fill); the file-size
// limit fails writes the same way, from inside the process: every file
// larger than 24 kB (the images, the larger tables and figures) cannot be
// written. The earlier output stays whole, nothing is left beside it, and the
// error names the file.
TEST_CASE("a write that fails part-way, as on a full disk, leaves the earlier output whole and nothing beside it",
          "[apps][kill]") {
  const auto root = testing::TempDir("full_disk");
  const std::string data = (root / "data").string(), map = (root / "map").string();
  auto simulate = [&](const char* frames) {
    return std::vector<std::string>{"simulate", "--scenario", "office-change", "--frames", frames,
                                    "-o",       data,           "--threads",     "1",      "--quiet"};
  };
  const std::vector<std::string> mapping = {"map", data, "-o", map, "--quiet", "--threads", "1"};
  REQUIRE(RunProcess(simulate("60")) == 0);
  REQUIRE(RunProcess(mapping) == 0);
  const std::string frames = Slurp(std::filesystem::path(data) / "frames.csv");
  const std::string report = Slurp(std::filesystem::path(map) / "report.json");
  const std::vector<std::string> data_files = Listing(std::filesystem::path(data) / "images");
  const auto log = (root / "log").string();
  constexpr rlim_t kLimit = 24 * 1024;

  CHECK(RunProcess(simulate("80"), {}, log, kLimit) == 1);
  std::string err = Slurp(log);
  CHECK(err.find("write failed: File too large") != std::string::npos);
  CHECK(err.find("/images/000") != std::string::npos);  // the image it could not write
  CHECK(Slurp(std::filesystem::path(data) / "frames.csv") == frames);
  CHECK(Listing(std::filesystem::path(data) / "images") == data_files);
  CHECK(ReadDataset(data).frames.size() == 60);

  CHECK(RunProcess(mapping, {}, log, kLimit) == 1);
  err = Slurp(log);
  CHECK(err.find("write failed: File too large") != std::string::npos);
  CHECK(Slurp(std::filesystem::path(map) / "report.json") == report);
  CheckNoTornFile(map);
  std::filesystem::remove(log);
  CHECK(Listing(root) == std::vector<std::string>{"data", "map"});  // no staging folder, no temporary file
  std::filesystem::remove_all(root);
}

TEST_CASE("a sweep killed at random points resumes without repeating a finished run", "[apps][kill][sweep][slow]") {
  const auto root = testing::TempDir("kill_sweep");
  REQUIRE(RunProcess({"generate-graph", "--poses", "300", "-o", (root / "g.g2o").string(), "--truth",
               (root / "t.g2o").string()}) == 0);
  std::ofstream(root / "sweep.yaml") << "output: runs.csv\n"
                                        "datasets:\n  - name: g\n    graph: g.g2o\n    truth: t.g2o\n"
                                        "policies: [random]\noutliers: [0, 20]\nseeds: 3\n"
                                        "methods: [switchable, dcs, none]\n";
  const std::vector<std::string> sweep = {"sweep", "--config", (root / "sweep.yaml").string(), "--jobs", "1",
                                          "--quiet"};
  const std::filesystem::path csv = root / "runs.csv";
  // Killed when the CSV holds a random number of finished runs, three times.
  auto rows_in = [&] {
    std::ifstream in(csv);
    std::string line;
    std::size_t n = 0;
    while (std::getline(in, line)) ++n;
    return n > 0 ? n - 1 : 0;  // the header
  };
  std::mt19937 rng(13);
  std::size_t rows = 0;
  for (int k = 0; k < 3; ++k) {
    const std::size_t target = std::min<std::size_t>(17, rows + std::uniform_int_distribution<std::size_t>(1, 5)(rng));
    CAPTURE(target);
    CHECK(RunProcess(sweep, [&] { return rows_in() >= target; }) == -1);
    CheckNoTornFile(root);
    const std::size_t now = ReadSweepCsv(csv).size();
    CHECK(now >= target);  // nothing finished is lost
    rows = now;
  }
  CHECK(rows > 0);
  const std::string log = (root / "rerun.log").string();
  REQUIRE(RunProcess(sweep, {}, log) == 0);
  INFO(Slurp(log));
  CHECK(Slurp(log).find("18 runs, " + std::to_string(rows) + " already in") != std::string::npos);
  const std::vector<SweepRow> all = ReadSweepCsv(csv);
  std::set<std::string> keys;
  for (const SweepRow& r : all) {
    keys.insert(r.at("dataset") + "," + r.at("policy") + "," + r.at("outliers") + "," + r.at("seed") + "," +
                r.at("method"));
  }
  CHECK(all.size() == 18);
  CHECK(keys.size() == 18);
  std::filesystem::remove_all(root);
}

}  // namespace
}  // namespace catgraph
