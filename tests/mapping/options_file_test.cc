#include "mapping/options_file.h"

#include <string>

#include "backend/io/file_error.h"
#include "tests/catch.h"

namespace catgraph::mapping {
namespace {

// Options unlike the defaults in every kind of field: numbers, flags,
// enums, a σ, optionals set and unset.
MapperOptions Unusual() {
  MapperOptions o = PresetOptions(OptionsPreset::kPaper);
  o.front_end.filter.num_particles = 321;
  o.front_end.filter.new_place.leave_probability = 1e-17;
  o.front_end.filter.new_place.log_offset = 12.5;
  o.front_end.filter.inference.motion_sigma = Eigen::Vector3d(0.03, 0.01, 0.1 / 3.0);
  o.front_end.filter.seed = 18'446'744'073'709'551'615ULL;
  o.front_end.graph_uncertainty.closure_sigma = Eigen::Vector3d(0.3, 0.2, 0.07);
  o.front_end.threads = 3;
  o.back_end.method = RobustMethod::kDcs;
  o.back_end.initial_guess = InitialGuess::kChordal;
  o.back_end.cost = RelativePoseCostType::kChordal;
  o.back_end.switch_function = SwitchFunction::kSigmoid;
  o.back_end.gate.probability = 0.99;
  o.back_end.gate.noise_scale.window = 7;
  o.back_end.refinement.settled_decrease = 2.5e-5;
  o.back_end.readmission.enabled = false;
  o.back_end.solver.num_threads = 2;
  o.hierarchy.policy = HierarchyPolicy::kFlat;
  o.online_max_iterations = 5;
  o.solve_online = false;
  o.observation.model = ObservationKind::kHolistic;
  o.observation.vocabulary.feature = FeatureType::kAkaze;
  o.observation.vocabulary.words = 250;
  o.observation.train_every = 4;
  o.observation.fabmap.p_observe_given_absent = 0.05;
  o.observation.holistic.width_px = 48;
  return o;
}

TEST_CASE("an options file written from options reads back to the same options", "[mapping][options]") {
  for (const MapperOptions& written : {MapperOptions{}, PresetOptions(OptionsPreset::kPaper), Unusual()}) {
    const std::string yaml = OptionsYaml(written);
    MapperOptions read = PresetOptions(OptionsPreset::kDefault);
    ReadOptions(yaml, "options.yaml", read);
    CHECK(OptionsYaml(read) == yaml);
  }
  // The fields themselves, not only their text.
  MapperOptions read;
  ReadOptions(OptionsYaml(Unusual()), "options.yaml", read);
  const CatGraphOptions& f = read.front_end.filter;
  CHECK(f.num_particles == 321);
  CHECK(f.new_place.leave_probability == 1e-17);
  CHECK(f.new_place.log_offset == 12.5);
  REQUIRE(f.inference.motion_sigma.has_value());
  CHECK(f.inference.motion_sigma->z() == 0.1 / 3.0);  // every digit of a double
  CHECK_FALSE(f.new_place.motion_sigma.has_value());  // the paper's: unset
  CHECK(f.seed == 18'446'744'073'709'551'615ULL);
  CHECK_FALSE(f.recognition.forward_camera);
  CHECK(read.back_end.method == RobustMethod::kDcs);
  CHECK(read.back_end.cost == RelativePoseCostType::kChordal);
  CHECK(read.back_end.switch_function == SwitchFunction::kSigmoid);
  CHECK(read.back_end.gate.noise_scale.window == 7);
  CHECK_FALSE(read.back_end.readmission.enabled);
  CHECK(read.hierarchy.policy == HierarchyPolicy::kFlat);
  CHECK(read.online_max_iterations == 5);
  CHECK_FALSE(read.solve_online);
  CHECK(read.observation.model == ObservationKind::kHolistic);
  CHECK(read.observation.vocabulary.feature == FeatureType::kAkaze);
  CHECK(read.observation.vocabulary.words == 250);
  CHECK(read.observation.train_every == 4);
  CHECK(read.observation.fabmap.p_observe_given_absent == 0.05);
  CHECK(read.observation.holistic.width_px == 48);
}

TEST_CASE("an options file changes the fields it names and no other", "[mapping][options]") {
  MapperOptions o;
  ReadOptions("front_end:\n  filter:\n    num_particles: 500\n    new_place: {stay_fraction: 0.5, log_offset: ~}\n"
              "back_end:\n  refinement:\n    enabled: no\n",
              "mine.yaml", o);
  CHECK(o.front_end.filter.num_particles == 500);
  CHECK(o.front_end.filter.new_place.stay_fraction == 0.5);
  CHECK_FALSE(o.front_end.filter.new_place.log_offset.has_value());
  CHECK_FALSE(o.back_end.refinement.enabled);
  MapperOptions expected;
  expected.front_end.filter.num_particles = 500;
  expected.front_end.filter.new_place.stay_fraction = 0.5;
  expected.back_end.refinement.enabled = false;
  CHECK(OptionsYaml(o) == OptionsYaml(expected));
  // An empty file changes nothing.
  MapperOptions unchanged = Unusual();
  ReadOptions("", "empty.yaml", unchanged);
  CHECK(OptionsYaml(unchanged) == OptionsYaml(Unusual()));
}

TEST_CASE("an options file's mistakes name the file, the line and what was expected", "[mapping][options]") {
  auto error = [](const std::string& text) {
    MapperOptions o;
    const std::string before = OptionsYaml(o);
    try {
      ReadOptions(text, "bad.yaml", o);
    } catch (const FileError& e) {
      CHECK(OptionsYaml(o) == before);  // nothing half-read
      return std::string(e.what());
    }
    FAIL("no error for:\n" << text);
    return std::string();
  };
  CHECK_THAT(error("front_end:\n  filter:\n    particles: 10\n"),
             Catch::StartsWith("bad.yaml:3: unknown key 'particles' in front_end.filter; expected one of:") &&
                 Catch::Contains("num_particles"));
  CHECK_THAT(error("frontend: {}\n"), Catch::StartsWith("bad.yaml:1: unknown key 'frontend'; expected one of: "
                                                        "back_end, front_end, hierarchy, observation, online"));
  CHECK_THAT(error("front_end:\n  filter:\n    num_particles: many\n"),
             Catch::StartsWith("bad.yaml:3: 'num_particles': expected an integer"));
  CHECK_THAT(error("front_end:\n  filter:\n    motion_sigma: [0.05, 0.05]\n"),
             Catch::StartsWith("bad.yaml:3: 'motion_sigma': expected three numbers"));
  CHECK_THAT(error("front_end:\n  filter:\n    seed: -1\n"), Catch::StartsWith("bad.yaml:3: 'seed': expected an integer >= 0"));
  CHECK_THAT(error("back_end:\n  method: switchabel\n"),
             Catch::StartsWith("bad.yaml:2: 'method': 'switchabel' is not one of its names"));
  CHECK_THAT(error("back_end:\n  gate: 0.5\n"), Catch::StartsWith("bad.yaml:2: 'gate' is a section"));
  CHECK_THAT(error("front_end:\n  filter:\n    closure_threshold: .nan\n"),
             Catch::StartsWith("bad.yaml:3: 'closure_threshold': expected a finite number"));
  CHECK_THAT(error("- 1\n- 2\n"), Catch::StartsWith("bad.yaml:1: expected a map of options"));
  // Out of range: the library's own check, at the line of the field it names.
  CHECK_THAT(error("# mine\nfront_end:\n  filter:\n    new_place:\n      stay_fraction: 1.5\n"),
             Catch::StartsWith("bad.yaml:5: CatGraphOptions: new_place.stay_fraction must be in [0, 1]"));
  CHECK_THAT(error("front_end:\n  filter:\n    gate: {base_m: -1}\n"), Catch::StartsWith("bad.yaml:3: CatGraphOptions: gate.base_m"));
  CHECK_THAT(error("back_end:\n  solver:\n    max_iterations: 0\n"), Catch::StartsWith("bad.yaml:3: OptimizerOptions::max_iterations"));
  CHECK_THAT(error("back_end:\n  gate:\n    probability: 1\n"), Catch::StartsWith("bad.yaml:3: gate.probability must be in (0, 1)"));
  CHECK_THAT(error("online:\n  max_iterations: 0\n"), Catch::StartsWith("bad.yaml:2: MapperOptions: online_max_iterations"));
  CHECK_THAT(error("front_end:\n  graph_uncertainty:\n    closure_sigma: [0.1, 0, 0.1]\n"),
             Catch::StartsWith("bad.yaml:3: PoseGraphUncertainty: closure_sigma"));
  CHECK_THAT(error("observation:\n  vocabulary:\n    words: 1\n"),
             Catch::StartsWith("bad.yaml:3: ObservationOptions: vocabulary.words must be >= 2"));
  CHECK_THAT(error("observation:\n  fabmap:\n    p_observe_given_exists: 0\n"),
             Catch::StartsWith("bad.yaml:3: ObservationOptions: fabmap.p_observe_given_exists"));
  CHECK_THAT(error("observation:\n  holistic: {width_px: 2}\n"),
             Catch::StartsWith("bad.yaml:2: ObservationOptions: holistic.width_px"));
  CHECK_THAT(error("observation:\n  model: surf\n"), Catch::StartsWith("bad.yaml:2: 'model': 'surf' is not one of"));
  // coupled needs switches: the hierarchy's line.
  CHECK_THAT(error("back_end:\n  method: dcs\nhierarchy:\n  policy: coupled\n"), Catch::StartsWith("bad.yaml:"));
}

TEST_CASE("the presets: the defaults, and the paper's filter exactly", "[mapping][options]") {
  CHECK(OptionsYaml(PresetOptions(OptionsPreset::kDefault)) == OptionsYaml(MapperOptions{}));
  const CatGraphOptions paper = PresetOptions(OptionsPreset::kPaper).front_end.filter;
  Validate(paper);
  // Table I's Q, and none of the additions.
  CHECK(paper.motion_sigma == Eigen::Vector3d(0.05, 0.05, 0.005));
  CHECK(paper.new_place.leave_probability == paper.new_place_prior);
  CHECK_FALSE(paper.gate.enabled);
  CHECK(paper.inference.particle_factor == 1);
  CHECK(paper.inference.total_path_retries == 0);
  for (const OptionsPreset p : {OptionsPreset::kDefault, OptionsPreset::kPaper}) {
    CHECK(OptionsPresetFromString(ToString(p)) == p);
  }
  CHECK_FALSE(OptionsPresetFromString("spec").has_value());
}

}  // namespace
}  // namespace catgraph::mapping
