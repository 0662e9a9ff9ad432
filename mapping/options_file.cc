#include "mapping/options_file.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <yaml-cpp/yaml.h>

#include "backend/graph/name_table.h"
#include "backend/io/file_error.h"
#include "backend/io/internal/text_line.h"
#include "backend/io/yaml_text.h"

namespace catgraph::mapping {
namespace {

constexpr NameTable<OptionsPreset, 2> kPresetNames = {{
    {OptionsPreset::kDefault, "default"},
    {OptionsPreset::kPaper, "paper"},
}};
constexpr NameTable<RelativePoseCostType, 2> kCostNames = {{
    {RelativePoseCostType::kG2o, "g2o"},
    {RelativePoseCostType::kChordal, "chordal"},
}};
constexpr NameTable<SwitchFunction, 2> kSwitchFunctionNames = {{
    {SwitchFunction::kLinear, "linear"},
    {SwitchFunction::kSigmoid, "sigmoid"},
}};

std::string_view CostName(RelativePoseCostType cost) { return NameOf(kCostNames, cost); }
std::optional<RelativePoseCostType> CostFromName(std::string_view text) { return ValueOf(kCostNames, text); }
std::string_view SwitchFunctionName(SwitchFunction f) { return NameOf(kSwitchFunctionNames, f); }
std::optional<SwitchFunction> SwitchFunctionFromName(std::string_view text) {
  return ValueOf(kSwitchFunctionNames, text);
}

// An enum field and how it is spelt.
template <typename Enum>
struct EnumField {
  Enum& value;
  std::string_view (*to_string)(Enum);
  std::optional<Enum> (*from_string)(std::string_view);
};
template <typename Enum>
EnumField<Enum> Spelt(Enum& value, std::string_view (*to_string)(Enum),
                      std::optional<Enum> (*from_string)(std::string_view)) {
  return {value, to_string, from_string};
}

// The one list of the options and their keys; `v` reads or writes them:
// v.Field(key, value) for a value, v.Section(key, visit) for a nested struct.
template <typename V>
void VisitFilter(V& v, CatGraphOptions& o) {
  v.Field("num_particles", o.num_particles);
  v.Field("closure_threshold", o.closure_threshold);
  v.Field("hypothesis_radius_m", o.hypothesis_radius_m);
  v.Field("motion_sigma", o.motion_sigma);
  v.Field("ess_threshold", o.ess_threshold);
  v.Field("new_place_prior", o.new_place_prior);
  v.Field("exclusion_window_s", o.exclusion_window_s);
  v.Field("exclusion_window_m", o.exclusion_window_m);
  v.Field("heading_in_position_likelihood", o.heading_in_position_likelihood);
  v.Field("sequence_break_s", o.sequence_break_s);
  v.Field("motion_radius_m", o.motion_radius_m);
  v.Field("hypothesis_candidate_edges", o.hypothesis_candidate_edges);
  v.Field("seed", o.seed);
  v.Section("recognition", [&] {
    v.Field("closure_min_evidence", o.recognition.closure_min_evidence);
    v.Field("forward_camera", o.recognition.forward_camera);
    v.Field("observation_window_m", o.recognition.observation_window_m);
  });
  v.Section("new_place", [&] {
    v.Field("log_offset", o.new_place.log_offset);
    v.Field("leave_probability", o.new_place.leave_probability);
    v.Field("stay_fraction", o.new_place.stay_fraction);
    v.Field("stay_relative_offset", o.new_place.stay_relative_offset);
    v.Field("hold_after_closure", o.new_place.hold_after_closure);
    v.Field("motion_sigma", o.new_place.motion_sigma);
  });
  v.Section("gate", [&] {
    v.Field("enabled", o.gate.enabled);
    v.Field("base_m", o.gate.base_m);
    v.Field("fraction", o.gate.fraction);
  });
  v.Section("inference", [&] {
    v.Field("enabled", o.inference.enabled);
    v.Field("local_validation_m", o.inference.local_validation_m);
    v.Field("total_validation_m", o.inference.total_validation_m);
    v.Field("total_path_retries", o.inference.total_path_retries);
    v.Field("seed_local", o.inference.seed_local);
    v.Field("particle_factor", o.inference.particle_factor);
    v.Field("motion_sigma", o.inference.motion_sigma);
  });
}

template <typename V>
void VisitBackEnd(V& v, PoseGraphOptimizerOptions& o) {
  v.Field("method", Spelt(o.method, &catgraph::ToString, &RobustMethodFromString));
  v.Field("initial_guess", Spelt(o.initial_guess, &catgraph::ToString, &InitialGuessFromString));
  v.Field("cost", Spelt(o.cost, &CostName, &CostFromName));
  v.Field("switch_function", Spelt(o.switch_function, &SwitchFunctionName, &SwitchFunctionFromName));
  v.Section("gate", [&] {
    GateOptions& g = o.gate;
    v.Field("probability", g.probability);
    v.Field("estimate_noise_scale", g.estimate_noise_scale);
    v.Field("noise_scale_threshold", g.noise_scale_threshold);
    v.Section("noise_scale", [&] {
      v.Field("window", g.noise_scale.window);
      v.Field("max_cycles", g.noise_scale.max_cycles);
      v.Field("min_cycles", g.noise_scale.min_cycles);
      v.Field("quantile", g.noise_scale.quantile);
      v.Field("upper_quantile", g.noise_scale.upper_quantile);
    });
    v.Field("narrow", g.narrow);
    v.Field("narrow_max_tail_ratio", g.narrow_max_tail_ratio);
    v.Field("narrow_min_cycles", g.narrow_min_cycles);
    v.Field("narrow_max_rejected_share", g.narrow_max_rejected_share);
  });
  v.Field("switch_prior_information", o.switch_prior_information);
  v.Field("dcs_phi", o.dcs_phi);
  v.Field("loss_scale_sigma", o.loss_scale_sigma);
  v.Field("gnc_mu_step", o.gnc_mu_step);
  v.Field("gnc_max_rounds", o.gnc_max_rounds);
  v.Field("gnc_round_iterations", o.gnc_round_iterations);
  v.Field("robust_odometry", o.robust_odometry);
  v.Section("refinement", [&] {
    v.Field("enabled", o.refinement.enabled);
    v.Field("stop_when_settled", o.refinement.stop_when_settled);
    v.Field("settled_iterations", o.refinement.settled_iterations);
    v.Field("settled_decrease", o.refinement.settled_decrease);
  });
  v.Section("readmission", [&] { v.Field("enabled", o.readmission.enabled); });
  v.Section("solver", [&] {
    v.Field("max_iterations", o.solver.max_iterations);
    v.Field("function_tolerance", o.solver.function_tolerance);
    v.Field("gradient_tolerance", o.solver.gradient_tolerance);
    v.Field("parameter_tolerance", o.solver.parameter_tolerance);
    v.Field("num_threads", o.solver.num_threads);
  });
}

std::optional<FeatureType> FeatureFromName(std::string_view text) {
  for (const FeatureType f : {FeatureType::kSift, FeatureType::kOrb, FeatureType::kAkaze, FeatureType::kKaze}) {
    if (ToString(f) == text) return f;
  }
  return std::nullopt;
}

template <typename V>
void VisitObservation(V& v, ObservationOptions& o) {
  v.Field("model", Spelt(o.model, &catgraph::ToString, &ObservationKindFromString));
  v.Section("vocabulary", [&] {
    v.Field("feature", Spelt(o.vocabulary.feature, &catgraph::ToString, &FeatureFromName));
    v.Field("words", o.vocabulary.words);
    v.Field("kmeans_iterations", o.vocabulary.kmeans_iterations);
    v.Field("kmeans_attempts", o.vocabulary.kmeans_attempts);
    v.Field("max_descriptors", o.vocabulary.max_descriptors);
    v.Field("seed", o.vocabulary.seed);
  });
  v.Field("train_every", o.train_every);
  v.Section("fabmap", [&] {
    v.Field("p_observe_given_exists", o.fabmap.p_observe_given_exists);
    v.Field("p_observe_given_absent", o.fabmap.p_observe_given_absent);
    v.Field("naive_bayes", o.fabmap.naive_bayes);
    v.Field("new_place_log_offset", o.fabmap.new_place_log_offset);
  });
  v.Section("holistic", [&] {
    v.Field("width_px", o.holistic.width_px);
    v.Field("max_shift_fraction", o.holistic.max_shift_fraction);
    v.Field("reference_places", o.holistic.reference_places);
  });
}

template <typename V>
void VisitMapper(V& v, MapperOptions& o) {
  v.Section("observation", [&] { VisitObservation(v, o.observation); });
  v.Section("front_end", [&] {
    v.Section("filter", [&] { VisitFilter(v, o.front_end.filter); });
    v.Section("graph_uncertainty", [&] {
      PoseGraphUncertainty& u = o.front_end.graph_uncertainty;
      v.Field("odometry_m_per_sqrt_m", u.odometry_m_per_sqrt_m);
      v.Field("odometry_rad_per_sqrt_m", u.odometry_rad_per_sqrt_m);
      v.Field("min_distance_m", u.min_distance_m);
      v.Field("closure_sigma", u.closure_sigma);
      v.Field("share_inferred_information", u.share_inferred_information);
    });
    v.Field("threads", o.front_end.threads);
  });
  v.Section("back_end", [&] { VisitBackEnd(v, o.back_end); });
  v.Section("hierarchy", [&] {
    v.Field("policy", Spelt(o.hierarchy.policy, &catgraph::ToString, &HierarchyPolicyFromString));
    v.Field("max_rounds", o.hierarchy.max_rounds);
  });
  v.Section("online", [&] {
    v.Field("solve", o.solve_online);
    v.Field("max_iterations", o.online_max_iterations);
  });
}

// The shortest text that reads back as `value`.
std::string RoundTrip(double value) {
  char buffer[32];
  const auto [end, error] = std::to_chars(buffer, buffer + sizeof buffer, value);
  return error == std::errc() ? std::string(buffer, end) : std::to_string(value);
}

class Writer {
 public:
  template <typename T>
  void Field(const char* key, const T& value) {
    Line(key) << ' ' << Text(value) << '\n';
  }
  template <typename F>
  void Section(const char* key, F&& visit) {
    Line(key) << '\n';
    ++depth_;
    visit();
    --depth_;
  }
  std::string str() const { return out_.str(); }

 private:
  std::ostream& Line(const char* key) { return out_ << std::string(2 * depth_, ' ') << key << ':'; }
  static std::string Text(bool b) { return b ? "true" : "false"; }
  static std::string Text(double d) { return RoundTrip(d); }
  static std::string Text(int i) { return std::to_string(i); }
  static std::string Text(std::uint64_t i) { return std::to_string(i); }
  static std::string Text(const Eigen::Vector3d& s) {
    std::string text = "[";
    for (int i = 0; i < 3; ++i) {
      if (i > 0) text += ", ";
      text += RoundTrip(s[i]);
    }
    text += ']';
    return text;
  }
  template <typename T>
  static std::string Text(const std::optional<T>& o) {
    return o ? Text(*o) : "null";
  }
  template <typename Enum>
  static std::string Text(const EnumField<Enum>& e) {
    return std::string(e.to_string(e.value));
  }

  std::ostringstream out_;
  int depth_ = 0;
};

// Reads the keys a YAML map holds onto the fields the visit names; an
// unknown key is an error naming the keys of its section. Records the line
// of every field read, so that a validation error can name it.
class Reader {
 public:
  Reader(const YAML::Node& root, std::string source) : source_(std::move(source)) {
    if (!root.IsNull() && !root.IsMap()) Fail(root, "expected a map of options (key: value)");
    nodes_.push_back(root);
  }

  template <typename T>
  void Field(const char* key, T&& value) {
    const YAML::Node node = Child(key);
    if (!node) return;
    Read(node, key, value);
    lines_[Path(key)] = node.Mark().line + 1;
  }
  template <typename F>
  void Section(const char* key, F&& visit) {
    const YAML::Node node = Child(key);
    if (!node) return;
    if (!node.IsMap()) Fail(node, std::string("'") + key + "' is a section: expected a map of options");
    path_.push_back(key);
    nodes_.push_back(node);
    visit();
    CheckKnown();
    nodes_.pop_back();
    path_.pop_back();
  }
  // After the top level's visit.
  void Finish() { CheckKnown(); }

  // The line of the field read from the file that a validation message
  // names (FieldNamedBy over every tail of the fields' paths); 0 if none.
  int LineOf(const std::string& message) const {
    std::map<std::string, int> tails;
    for (const auto& [path, line] : lines_) {
      for (std::size_t from = 0;; ++from) {
        tails.emplace(path.substr(from), line);
        from = path.find('.', from);
        if (from == std::string::npos) break;
      }
    }
    std::vector<std::string> names;
    for (const auto& [tail, line] : tails) names.push_back(tail);
    const std::string named = FieldNamedBy(message, names);
    return named.empty() ? 0 : tails.at(named);
  }

 private:
  YAML::Node Child(const char* key) {
    const YAML::Node& map = nodes_.back();
    known_[Path("")].insert(key);
    if (map.IsNull()) return YAML::Node(YAML::NodeType::Undefined);
    const YAML::Node child = map[key];
    return child ? child : YAML::Node(YAML::NodeType::Undefined);
  }

  void CheckKnown() {
    const YAML::Node& map = nodes_.back();
    if (map.IsNull()) return;
    const std::set<std::string>& known = known_[Path("")];
    for (const auto& item : map) {
      const std::string key = item.first.Scalar();
      if (known.count(key) == 0) {
        std::string names;
        for (const std::string& k : known) {
          if (!names.empty()) names += ", ";
          names += k;
        }
        Fail(item.first, "unknown key '" + key + "'" + (path_.empty() ? "" : " in " + Path("")) +
                             "; expected one of: " + names);
      }
    }
  }

  std::string Path(const std::string& key) const {
    std::string p;
    for (const std::string& s : path_) {
      if (!p.empty()) p += '.';
      p += s;
    }
    if (!key.empty()) {
      if (!p.empty()) p += '.';
      p += key;
    }
    return p;
  }

  [[noreturn]] void Fail(const YAML::Node& node, const std::string& what) const {
    throw FileError(source_, node.Mark().line + 1, what);
  }

  template <typename T>
  T Scalar(const YAML::Node& node, const char* key, const char* expected) const {
    T value{};
    if (!node.IsScalar() || !YAML::convert<T>::decode(node, value)) {
      Fail(node, std::string("'") + key + "': expected " + expected);
    }
    return value;
  }
  void Read(const YAML::Node& node, const char* key, bool& value) const {
    value = Scalar<bool>(node, key, "true or false");
  }
  void Read(const YAML::Node& node, const char* key, int& value) const {
    value = Scalar<int>(node, key, "an integer");
  }
  void Read(const YAML::Node& node, const char* key, std::uint64_t& value) const {
    if (node.IsScalar() && !node.Scalar().empty() && node.Scalar()[0] == '-') {
      Fail(node, std::string("'") + key + "': expected an integer >= 0");
    }
    value = Scalar<std::uint64_t>(node, key, "an integer >= 0");
  }
  void Read(const YAML::Node& node, const char* key, double& value) const {
    value = Scalar<double>(node, key, "a number");
    if (!std::isfinite(value)) Fail(node, std::string("'") + key + "': expected a finite number");
  }
  void Read(const YAML::Node& node, const char* key, Eigen::Vector3d& value) const {
    if (!node.IsSequence() || node.size() != 3) {
      Fail(node, std::string("'") + key + "': expected three numbers [x, y, theta]");
    }
    for (int i = 0; i < 3; ++i) Read(node[static_cast<std::size_t>(i)], key, value[i]);
  }
  template <typename T>
  void Read(const YAML::Node& node, const char* key, std::optional<T>& value) const {
    if (node.IsNull()) {
      value.reset();
      return;
    }
    T v{};
    Read(node, key, v);
    value = v;
  }
  template <typename Enum>
  void Read(const YAML::Node& node, const char* key, const EnumField<Enum>& field) const {
    const std::string text = node.IsScalar() ? node.Scalar() : std::string();
    const std::optional<Enum> e = field.from_string(text);
    if (!e) Fail(node, std::string("'") + key + "': '" + text + "' is not one of its names");
    field.value = *e;
  }

  std::string source_;
  std::vector<YAML::Node> nodes_;
  std::vector<std::string> path_;
  std::map<std::string, std::set<std::string>> known_;  // section path -> its keys
  std::map<std::string, int> lines_;                    // field path -> line
};

}  // namespace

std::string FieldNamedBy(const std::string& message, const std::vector<std::string>& fields) {
  auto in_name = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.'; };
  std::string best;
  for (const std::string& field : fields) {
    if (field.empty() || field.size() <= best.size()) continue;
    for (std::size_t at = message.find(field); at != std::string::npos; at = message.find(field, at + 1)) {
      const std::size_t end = at + field.size();
      const bool starts = at == 0 || !in_name(message[at - 1]);
      // A full stop ending the message is no part of the name.
      const bool ends = end == message.size() || !in_name(message[end]) ||
                        (message[end] == '.' && (end + 1 == message.size() || message[end + 1] == ' '));
      if (starts && ends) {
        best = field;
        break;
      }
    }
  }
  return best;
}

std::string_view ToString(OptionsPreset preset) { return NameOf(kPresetNames, preset); }
std::optional<OptionsPreset> OptionsPresetFromString(std::string_view text) { return ValueOf(kPresetNames, text); }
std::vector<std::string> OptionsPresetNames() { return NamesOf(kPresetNames); }

MapperOptions PresetOptions(OptionsPreset preset) {
  MapperOptions options;
  if (preset == OptionsPreset::kPaper) options.front_end.filter = CatGraphOptions::Paper();
  return options;
}

void ReadOptions(const std::string& text, const std::string& source, MapperOptions& options) {
  MapperOptions read = options;
  const YAML::Node root = LoadYamlWithoutAliases(text, source);
  Reader reader(root, source);
  VisitMapper(reader, read);
  reader.Finish();
  // Validated by the libraries; the field the message names gives the line.
  try {
    Validate(read);
  } catch (const std::invalid_argument& e) {
    throw FileError(source, reader.LineOf(e.what()), e.what());
  }
  options = std::move(read);
}

void ReadOptionsFile(const std::filesystem::path& path, MapperOptions& options) {
  constexpr std::uintmax_t kMaxOptionsBytes = 1 << 20;
  ReadOptions(ReadWholeFile(path, kMaxOptionsBytes, "an options file (YAML)"), path.string(), options);
}

std::string OptionsYaml(const MapperOptions& options) {
  MapperOptions copy = options;
  Writer writer;
  VisitMapper(writer, copy);
  return writer.str();
}

}  // namespace catgraph::mapping
