#include "experiments/sweep.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <fstream>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include "apps/plot/figure.h"
#include "backend/evaluation.h"
#include "backend/io/atomic_file.h"
#include "backend/io/file_error.h"
#include "backend/io/internal/text_line.h"
#include "backend/io/graph_io.h"
#include "backend/io/trajectory_io.h"
#include "backend/io/json_integer.h"
#include "backend/io/yaml_text.h"

namespace catgraph {
namespace {

// ---------------------------------------------------------------- config

nlohmann::json YamlToJson(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Sequence: {
      nlohmann::json j = nlohmann::json::array();
      for (const auto& item : node) j.push_back(YamlToJson(item));
      return j;
    }
    case YAML::NodeType::Map: {
      nlohmann::json j = nlohmann::json::object();
      for (const auto& item : node) j[item.first.as<std::string>()] = YamlToJson(item.second);
      return j;
    }
    case YAML::NodeType::Scalar: {
      const std::string text = node.Scalar();
      if (node.Tag() == "!") return text;  // quoted: always a string
      std::int64_t i = 0;
      double d = 0.0;
      bool b = false;
      if (YAML::convert<std::int64_t>::decode(node, i)) return i;
      if (YAML::convert<double>::decode(node, d)) return d;
      if (YAML::convert<bool>::decode(node, b)) return b;
      return text;
    }
    default: return nullptr;
  }
}

template <typename T, typename Parse>
std::vector<T> ListOf(const nlohmann::json& j, const char* key, Parse parse) {
  std::vector<T> values;
  const nlohmann::json& list = j.at(key);
  if (!list.is_array() || list.empty()) {
    throw std::invalid_argument(std::string("'") + key + "' must be a non-empty list");
  }
  for (const auto& item : list) values.push_back(parse(item));
  return values;
}

OutlierOptions OutlierOptionsFor(const SweepConfig& c, OutlierPolicy policy, int count,
                                 std::uint64_t seed) {
  OutlierOptions o;
  o.policy = policy;
  o.count = count;
  // Random and local place single edges; the group size is for the others.
  const bool single = policy == OutlierPolicy::kRandom || policy == OutlierPolicy::kLocal;
  o.group_size = single ? 0 : c.group_size;
  o.local_window = c.local_window;
  o.seed = seed;
  return o;
}

SweepConfig ParseConfig(const nlohmann::json& j, const std::filesystem::path& base) {
  static const std::set<std::string> kKeys = {
      "datasets", "methods",  "policies",       "outliers",          "seeds",  "group_size",
      "local_window", "init", "max_iterations", "switch_gate_probability", "refine", "output"};
  if (!j.is_object()) throw std::invalid_argument("expected a mapping of sweep settings");
  for (const auto& [key, value] : j.items()) {
    if (!kKeys.contains(key)) throw std::invalid_argument("unknown key '" + key + "'");
  }
  SweepConfig c;
  auto path_of = [&base](const std::string& p) {
    const std::filesystem::path path(p);
    return path.is_absolute() ? path : base / path;
  };
  c.datasets = ListOf<SweepDataset>(j, "datasets", [&](const nlohmann::json& d) {
    SweepDataset ds{d.at("name").get<std::string>(), path_of(d.at("graph").get<std::string>()), {}};
    if (d.contains("truth")) ds.truth = path_of(d.at("truth").get<std::string>());
    constexpr std::string_view kNameCharacters =
        "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_.-";
    if (ds.name.empty() || ds.name.find_first_not_of(kNameCharacters) != std::string::npos) {
      throw std::invalid_argument("dataset name '" + ds.name +
                                  "' must be letters, digits, '_', '.' or '-'");
    }
    return ds;
  });
  std::set<std::string> names;
  for (const SweepDataset& d : c.datasets) {
    if (!names.insert(d.name).second) {
      throw std::invalid_argument("dataset name '" + d.name + "' is used twice");
    }
  }
  if (j.contains("methods")) {
    c.methods = ListOf<RobustMethod>(j, "methods", [](const nlohmann::json& m) {
      const auto v = RobustMethodFromString(m.get<std::string>());
      if (!v) throw std::invalid_argument("unknown method '" + m.get<std::string>() + "'");
      return *v;
    });
  }
  if (j.contains("policies")) {
    c.policies = ListOf<OutlierPolicy>(j, "policies", [](const nlohmann::json& p) {
      const auto v = OutlierPolicyFromString(p.get<std::string>());
      if (!v) throw std::invalid_argument("unknown policy '" + p.get<std::string>() + "'");
      return *v;
    });
  }
  if (j.contains("outliers")) {
    c.outliers = ListOf<int>(j, "outliers", [](const nlohmann::json& n) {
      return static_cast<int>(IntegerIn(n, "outliers", 0, kMaxOutliers));
    });
  }
  if (j.contains("seeds")) {
    if (j.at("seeds").is_number()) {  // "seeds: 5" means 1 ... 5
      c.seeds.clear();
      const auto count = IntegerIn(j.at("seeds"), "seeds", 1, 100'000);
      for (std::int64_t s = 1; s <= count; ++s) c.seeds.push_back(static_cast<std::uint64_t>(s));
    } else {
      c.seeds = ListOf<std::uint64_t>(j, "seeds", [](const nlohmann::json& s) {
        if (!s.is_number_integer() || (!s.is_number_unsigned() && s.get<std::int64_t>() < 0)) {
          throw std::invalid_argument("'seeds' must list integers >= 0, not " + s.dump());
        }
        return s.get<std::uint64_t>();
      });
    }
  }
  c.group_size = static_cast<int>(IntegerIn(j, "group_size", 0, 0, 1'000'000));
  c.local_window = static_cast<int>(IntegerIn(j, "local_window", 20, 0, 1'000'000));
  if (j.contains("init")) {
    const auto init = InitialGuessFromString(j.at("init").get<std::string>());
    if (!init) throw std::invalid_argument("unknown init '" + j.at("init").get<std::string>() + "'");
    c.optimizer.initial_guess = *init;
  }
  c.optimizer.solver.max_iterations =
      static_cast<int>(IntegerIn(j, "max_iterations", c.optimizer.solver.max_iterations, 0, 1'000'000));
  c.optimizer.gate.probability =
      j.value("switch_gate_probability", c.optimizer.gate.probability);
  c.optimizer.refinement.enabled = j.value("refine", c.optimizer.refinement.enabled);
  if (j.contains("output")) c.output = path_of(j.at("output").get<std::string>());
  Validate(c.optimizer);
  for (OutlierPolicy p : c.policies) Validate(OutlierOptionsFor(c, p, 0, 1));
  return c;
}

// ---------------------------------------------------------------- CSV

std::string FormatDouble(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.9g", v);
  return buffer;
}

std::vector<std::string> SplitCsvLine(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream in(line);
  std::string field;
  while (std::getline(in, field, ',')) fields.push_back(field);
  if (!line.empty() && line.back() == ',') fields.emplace_back();
  return fields;
}

std::string HeaderLine() {
  std::string header;
  for (const std::string& c : SweepColumns()) header += (header.empty() ? "" : ",") + c;
  return header;
}

// Reads the finished rows of a sweep CSV; with `repair`, cuts a trailing
// incomplete line (a run interrupted while writing) off the file, but only
// once the rest has been read as a sweep CSV.
std::vector<SweepRow> ReadRows(const std::filesystem::path& path, bool repair) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FileError(path.string(), 0, "cannot open the sweep CSV");
  std::stringstream buffer;
  buffer << in.rdbuf();
  std::string content = buffer.str();
  std::vector<SweepRow> rows;
  if (content.empty()) return rows;
  const std::size_t complete = content.rfind('\n') == std::string::npos ? 0 : content.rfind('\n') + 1;
  if (complete == 0) {
    throw FileError(path.string(), 1, "expected the sweep CSV header '" + HeaderLine() + "'");
  }
  if (complete < content.size() && !repair) {
    throw FileError(path.string(), 0, "the last line is incomplete (an interrupted sweep?); "
                                      "rerun the sweep to repair it");
  }
  std::stringstream lines(content.substr(0, complete));
  std::string line;
  int number = 0;
  const auto& columns = SweepColumns();
  while (std::getline(lines, line)) {
    ++number;
    if (number == 1) {
      if (line != HeaderLine()) {
        throw FileError(path.string(), 1,
                        "expected the sweep CSV header '" + HeaderLine() +
                            "' (a CSV from another catgraph version or another tool?)");
      }
      continue;
    }
    const std::vector<std::string> fields = SplitCsvLine(line);
    if (fields.size() != columns.size()) {
      throw FileError(path.string(), number,
                      "found " + std::to_string(fields.size()) + " fields; expected " +
                          std::to_string(columns.size()));
    }
    SweepRow row;
    for (std::size_t k = 0; k < columns.size(); ++k) row[columns[k]] = fields[k];
    rows.push_back(std::move(row));
  }
  if (complete < content.size()) {
    in.close();
    std::filesystem::resize_file(path, complete);
  }
  return rows;
}

std::string KeyOf(const SweepRow& row) {
  return row.at("dataset") + "," + row.at("policy") + "," + row.at("outliers") + "," +
         row.at("seed") + "," + row.at("method");
}

// Appends whole lines with one write(2) each and syncs, so a crash leaves at
// most one incomplete line, which ReadRows(repair) removes. Holds an
// exclusive lock on the file while it lives: a second sweep on the same CSV
// is refused rather than running every row twice.
class CsvAppender {
 public:
  explicit CsvAppender(const std::filesystem::path& path) : path_(path.string()) {
    fd_ = ::open(path_.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) throw FileError(path_, 0, "cannot open the sweep CSV for appending");
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      ::close(fd_);
      throw FileError(path_, 0, "another sweep is writing this CSV; wait for it or give another -o");
    }
  }
  ~CsvAppender() { ::close(fd_); }
  CsvAppender(const CsvAppender&) = delete;
  CsvAppender& operator=(const CsvAppender&) = delete;

  void Append(const std::string& line) {
    const std::string text = line + '\n';
    std::size_t written = 0;
    while (written < text.size()) {
      const ssize_t n = ::write(fd_, text.data() + written, text.size() - written);
      if (n < 0) throw FileError(path_, 0, "write failed (disk full?)");
      written += static_cast<std::size_t>(n);
    }
    ::fsync(fd_);
  }

 private:
  std::string path_;
  int fd_ = -1;
};

// ---------------------------------------------------------------- runs

struct LoadedDataset {
  AnyPoseGraph graph;
  std::optional<AnyTrajectory> truth;
};

struct RunResult {
  std::string line;  // the CSV line, without newline
  bool usable = true;
};

RunResult Run(const SweepRun& run, const SweepConfig& config, const LoadedDataset& data) {
  AnyPoseGraph graph = data.graph;
  const OutlierOptions outliers = OutlierOptionsFor(config, run.policy, run.outliers, run.seed);
  const std::vector<InjectedClosure> injected = InjectOutliers(graph, outliers);
  const std::vector<ClosureLabel> labels = LabelClosures(graph, injected);
  PoseGraphOptimizerOptions options = config.optimizer;
  options.method = run.method;
  options.solver.num_threads = 1;  // the sweep runs one solve per core
  const PoseGraphOptimization result = OptimizePoseGraph(graph, options);
  const bool usable = result.summary.IsUsable();

  std::vector<ClosureOutcome> outcomes;
  for (const ClosureDecision& d : result.closures) outcomes.push_back({d.from, d.to, d.accepted});
  const ClosureScores scores = ScoreClosures(outcomes, labels);
  std::string ate = "", anchored = "";
  if (usable && data.truth) {
    const TrajectoryEvaluation t = EvaluateTrajectory(TrajectoryOf(result.graph), *data.truth);
    ate = FormatDouble(t.ate_m.rmse);
    anchored = FormatDouble(t.rmse_anchored_m);
  }
  const std::vector<std::string> fields = {
      run.dataset, std::string(ToString(run.policy)), std::to_string(run.outliers),
      std::to_string(run.seed), std::string(ToString(run.method)),
      std::to_string(GroupSize(outliers)), usable ? "ok" : "failed",
      std::to_string(result.summary.iterations),
      std::to_string(result.refinement ? result.refinement->iterations : 0),
      FormatDouble(result.TotalTimeS()),
      FormatDouble(result.chi2), std::to_string(result.accepted), std::to_string(result.rejected),
      ate, anchored, FormatDouble(scores.precision), FormatDouble(scores.recall),
      FormatDouble(scores.f1), std::to_string(scores.true_positives),
      std::to_string(scores.false_positives), std::to_string(scores.true_negatives),
      std::to_string(scores.false_negatives)};
  RunResult out{"", usable};
  for (const std::string& f : fields) out.line += (out.line.empty() ? "" : ",") + f;
  return out;
}

// The runs of one cell of the grid (all seeds), summarised.
struct CellStatistics {
  int runs = 0;
  std::vector<double> ate_values;  // of the runs with a usable solve and a truth
  ErrorStatistics ate;             // over ate_values
  double precision = 0.0, recall = 0.0, time_s = 0.0;  // means over the runs

  void Add(const SweepRow& row) {
    const double n = ++runs;
    auto running_mean = [n](double& mean, const std::string& text) {
      mean += (std::stod(text) - mean) / n;
    };
    running_mean(precision, row.at("precision"));
    running_mean(recall, row.at("recall"));
    running_mean(time_s, row.at("time_s"));
    if (!row.at("ate_rmse").empty()) {
      ate_values.push_back(std::stod(row.at("ate_rmse")));
      ate = StatisticsOf(ate_values);
    }
  }
};

std::string Fixed(double v, int digits = 3) {
  if (!std::isfinite(v)) return "-";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.*f", digits, v);
  return buffer;
}

plot::Axes SweepAxes(const std::string& policy, const std::string& y_label) {
  plot::Axes a;
  a.title = policy;
  a.x_label = "outliers";
  a.y_label = y_label;
  a.x_scale = plot::Scale::kSymlog;
  return a;
}

}  // namespace

// ---------------------------------------------------------------- public

SweepConfig ReadSweepConfigFile(const std::filesystem::path& path) {
  const std::string name = path.string();
  // A configuration is a few hundred bytes; 1 MB bounds what a hostile one costs.
  const std::string text = ReadWholeFile(path, std::uintmax_t{1} << 20, "a sweep configuration (JSON or YAML)");
  const std::string ext = "." + plot::LowerCaseExtension(path);
  nlohmann::json j;
  try {
    if (ext == ".yaml" || ext == ".yml") {
      j = YamlToJson(LoadYamlWithoutAliases(text, name));
    } else {
      j = nlohmann::json::parse(text);
    }
  } catch (const YAML::Exception& e) {
    throw FileError(name, e.mark.line + 1, "invalid YAML: " + e.msg);
  } catch (const nlohmann::json::exception& e) {
    throw FileError(name, 0, std::string("invalid JSON: ") + e.what());
  }
  try {
    return ParseConfig(j, path.parent_path());
  } catch (const nlohmann::json::exception& e) {
    throw FileError(name, 0, std::string("bad sweep configuration: ") + e.what() +
                                 " (docs/sweep.md lists the keys)");
  } catch (const std::invalid_argument& e) {
    throw FileError(name, 0, std::string("bad sweep configuration: ") + e.what());
  }
}

std::string SweepRun::Key() const {
  return dataset + "," + std::string(ToString(policy)) + "," + std::to_string(outliers) + "," +
         std::to_string(seed) + "," + std::string(ToString(method));
}

std::vector<SweepRun> SweepGrid(const SweepConfig& config) {
  std::vector<SweepRun> runs;
  for (const SweepDataset& d : config.datasets) {
    for (OutlierPolicy p : config.policies) {
      for (int n : config.outliers) {
        for (std::uint64_t s : config.seeds) {
          for (RobustMethod m : config.methods) {
            runs.push_back({runs.size(), d.name, p, n, s, m});
          }
        }
      }
    }
  }
  return runs;
}

Shard ParseShard(const std::string& text) {
  Shard shard;
  char slash = 0;
  std::istringstream in(text);
  if (!(in >> shard.index >> slash >> shard.count) || slash != '/' || !in.eof() ||
      shard.count < 1 || shard.index < 0 || shard.index >= shard.count) {
    throw std::invalid_argument("--shard: expected i/n with 0 <= i < n, got '" + text + "'");
  }
  return shard;
}

const std::vector<std::string>& SweepColumns() {
  static const std::vector<std::string> kColumns = {
      "dataset",  "policy",        "outliers",  "seed",           "method",
      "group_size", "status",      "iterations", "refine_iterations", "time_s", "chi2",
      "accepted", "rejected",      "ate_rmse",  "rmse_anchored",  "precision",
      "recall",   "f1",            "true_positives", "false_positives", "true_negatives",
      "false_negatives"};
  return kColumns;
}

std::vector<SweepRow> ReadSweepCsv(const std::filesystem::path& path) {
  return ReadRows(path, /*repair=*/false);
}

SweepSummary RunSweep(const SweepConfig& config, const SweepOptions& options) {
  if (config.output.empty()) throw std::invalid_argument("the sweep has no output CSV");
  if (options.shard.count < 1 || options.shard.index < 0 ||
      options.shard.index >= options.shard.count) {
    throw std::invalid_argument("bad shard");
  }
  // Finished runs, and a fresh file with its header. The lock is taken
  // first, so that a second sweep neither reads nor repairs the file.
  CsvAppender csv(config.output);
  std::set<std::string> finished;
  std::error_code ec;
  if (std::filesystem::file_size(config.output, ec) > 0) {
    for (const SweepRow& row : ReadRows(config.output, /*repair=*/true)) finished.insert(KeyOf(row));
  } else {
    csv.Append(HeaderLine());
  }
  SweepSummary summary;
  std::vector<SweepRun> todo;
  for (const SweepRun& run : SweepGrid(config)) {
    if (static_cast<int>(run.index % static_cast<std::size_t>(options.shard.count)) != options.shard.index) continue;
    ++summary.planned;
    if (finished.contains(run.Key())) {
      ++summary.resumed;
    } else {
      todo.push_back(run);
    }
  }
  if (todo.empty()) return summary;

  std::map<std::string, LoadedDataset> data;
  for (const SweepDataset& d : config.datasets) {
    LoadedDataset loaded{ReadGraphFile(d.graph).graph, std::nullopt};
    if (!d.truth.empty()) loaded.truth = ReadTrajectoryFile(d.truth);
    data.emplace(d.name, std::move(loaded));
  }

  std::mutex mutex;  // guards csv, summary, progress and error
  std::exception_ptr error;
  std::atomic<std::size_t> next{0};
  const auto start = std::chrono::steady_clock::now();
  auto worker = [&] {
    while (true) {
      {
        std::lock_guard lock(mutex);
        if (error) return;
      }
      if (options.stop && options.stop->load()) return;
      const std::size_t k = next.fetch_add(1);
      if (k >= todo.size()) return;
      try {
        const RunResult result = Run(todo[k], config, data.at(todo[k].dataset));
        std::lock_guard lock(mutex);
        csv.Append(result.line);
        ++summary.finished;
        summary.failed += !result.usable;
        if (options.on_progress) {
          const double elapsed =
              std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
          options.on_progress({summary.finished, todo.size(), summary.resumed, elapsed});
        }
      } catch (...) {
        std::lock_guard lock(mutex);
        if (!error) error = std::current_exception();
        return;
      }
    }
  };
  const int jobs = options.jobs > 0 ? options.jobs
                                    : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  std::vector<std::jthread> threads;  // joined on the way out should starting one fail
  for (int t = 0; t < std::min<int>(jobs, static_cast<int>(todo.size())); ++t) threads.emplace_back(worker);
  for (std::jthread& t : threads) t.join();
  if (error) std::rethrow_exception(error);
  summary.stopped = summary.finished < todo.size();
  return summary;
}

void MergeSweepCsv(const std::vector<std::filesystem::path>& inputs,
                   const std::filesystem::path& output) {
  std::map<std::string, SweepRow> rows;
  for (const auto& path : inputs) {
    for (SweepRow& row : ReadSweepCsv(path)) rows.try_emplace(KeyOf(row), std::move(row));
  }
  WriteFileAtomically(output, [&rows](std::ostream& out) {
    out << HeaderLine() << '\n';
    for (const auto& [key, row] : rows) {
      std::string line;
      for (const std::string& c : SweepColumns()) line += (line.empty() ? "" : ",") + row.at(c);
      out << line << '\n';
    }
  });
}

std::vector<std::filesystem::path> PlotSweep(const std::filesystem::path& csv,
                                             const std::string& prefix) {
  const std::vector<SweepRow> rows = ReadSweepCsv(csv);
  // dataset -> policy -> method -> outlier count -> its runs; policies and
  // methods in the order of their enums, as a configuration lists them.
  using Named = std::pair<int, std::string>;
  auto policy_rank = [](const std::string& name) {
    const auto p = OutlierPolicyFromString(name);
    return Named(p ? static_cast<int>(*p) : 99, name);
  };
  auto method_rank = [](const std::string& name) {
    const auto m = RobustMethodFromString(name);
    return Named(m ? static_cast<int>(*m) : 99, name);
  };
  std::map<std::string, std::map<Named, std::map<Named, std::map<int, CellStatistics>>>> cells;
  for (const SweepRow& r : rows) {
    cells[r.at("dataset")][policy_rank(r.at("policy"))][method_rank(r.at("method"))]
         [std::stoi(r.at("outliers"))].Add(r);
  }
  std::vector<std::filesystem::path> written;
  for (const auto& [dataset, policies] : cells) {
    // The outlier-free optimum: plain least squares without outliers.
    std::optional<double> reference;
    for (const auto& [policy, methods] : policies) {
      const auto none = methods.find(method_rank("none"));
      if (none != methods.end() && none->second.contains(0)) {
        reference = none->second.at(0).ate.mean;
        break;
      }
    }
    plot::Figure figure;
    figure.cols = static_cast<int>(policies.size());
    figure.rows = 3;
    figure.width_px = 380 * figure.cols;
    figure.height_px = 900;
    figure.title = dataset + ": false-positive sweep (means over seeds)";
    std::vector<plot::Axes> panels[3];  // ATE, precision, recall
    std::ostringstream md;
    md << "# Sweep on " << dataset << "\n\nFrom `" << csv.filename().string()
       << "`; every figure is over the seeds of its cell. ATE in metres after rigid "
          "alignment. Success: ATE within 1.5x the outlier-free optimum ("
       << (reference ? FormatDouble(*reference) + " m" : "unknown: no run of method none "
                                                         "with 0 outliers")
       << ").\n";
    for (const auto& [policy, methods] : policies) {
      plot::Axes ate = SweepAxes(policy.second, "ATE RMSE (m)");
      ate.y_scale = plot::Scale::kLog;
      plot::Axes precision = SweepAxes(policy.second, "precision");
      plot::Axes recall = SweepAxes(policy.second, "recall");
      for (plot::Axes* a : {&precision, &recall}) {
        a->y_min = -0.02;
        a->y_max = 1.02;
        a->legend = false;
      }
      for (const auto& [method, by_count] : methods) {
        plot::Series line;
        line.label = method.second;
        line.color = plot::PaletteColor(method.first);
        line.markers = true;
        plot::Series p = line, r = line;
        for (const auto& [count, cell] : by_count) {
          line.x.push_back(count);
          line.y.push_back(cell.ate.count > 0 ? cell.ate.mean : std::nan(""));
          p.x.push_back(count);
          p.y.push_back(cell.precision);
          r.x.push_back(count);
          r.y.push_back(cell.recall);
        }
        ate.series.push_back(std::move(line));
        precision.series.push_back(std::move(p));
        recall.series.push_back(std::move(r));
      }
      panels[0].push_back(std::move(ate));
      panels[1].push_back(std::move(precision));
      panels[2].push_back(std::move(recall));

      std::set<int> counts;
      for (const auto& [method, by_count] : methods) {
        for (const auto& [count, cell] : by_count) counts.insert(count);
      }
      md << "\n## " << policy.second
         << "\n\n| outliers | method | runs | ATE mean (m) | ATE median (m) | ATE max (m) | "
            "success | precision | recall | solve time (s) |\n"
            "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
      for (int count : counts) {
        for (const auto& [method, by_count] : methods) {
          const auto it = by_count.find(count);
          if (it == by_count.end()) continue;
          const CellStatistics& c = it->second;
          int successes = 0;
          for (double a : c.ate_values) successes += reference && a <= 1.5 * *reference;
          md << "| " << count << " | " << method.second << " | " << c.runs << " | "
             << Fixed(c.ate.mean) << " | " << Fixed(c.ate.median) << " | " << Fixed(c.ate.max)
             << " | " << successes << "/" << c.runs << " | " << Fixed(c.precision, 4) << " | "
             << Fixed(c.recall, 4) << " | " << Fixed(c.time_s, 2) << " |\n";
        }
      }
    }
    for (auto& row : panels) {
      for (plot::Axes& a : row) figure.axes.push_back(std::move(a));
    }
    const std::string stem = prefix + "-" + dataset;
    for (const char* ext : {".png", ".svg"}) {
      plot::SaveFigure(figure, stem + ext);
      written.emplace_back(stem + ext);
    }
    WriteFileAtomically(stem + ".md", [&md](std::ostream& out) { out << md.str(); });
    written.emplace_back(stem + ".md");
  }
  return written;
}

}  // namespace catgraph
