#include "frontend/cat_graph_options.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace catgraph {

bool IsValidSigma(const Eigen::Vector3d& sigma) { return (sigma.array() > 0.0).all() && sigma.allFinite(); }

void Validate(const CatGraphOptions& o) {
  auto fail = [](const std::string& what) { throw std::invalid_argument("CatGraphOptions: " + what); };
  if (o.num_particles < 1 || o.num_particles > kMaxParticles) {
    fail("num_particles must be from 1 to " + std::to_string(kMaxParticles));
  }
  if (!(o.closure_threshold > 0.0 && o.closure_threshold <= 1.0)) fail("closure_threshold must be in (0, 1]");
  if (!(o.hypothesis_radius_m > 0.0)) fail("hypothesis_radius_m must be > 0");
  if (!IsValidSigma(o.motion_sigma)) fail("motion_sigma must be finite and > 0");
  if (!(o.ess_threshold > 0.0 && o.ess_threshold <= 1.0)) fail("ess_threshold must be in (0, 1]");
  if (!(o.new_place_prior > 0.0 && o.new_place_prior < 1.0)) fail("new_place_prior must be in (0, 1)");
  if (!(o.exclusion_window_s >= 0.0)) fail("exclusion_window_s must be >= 0");
  if (!(o.exclusion_window_m >= 0.0)) fail("exclusion_window_m must be >= 0");
  if (!(o.sequence_break_s > 0.0)) fail("sequence_break_s must be > 0");
  if (!(o.motion_radius_m > 0.0)) fail("motion_radius_m must be > 0");
  if (o.hypothesis_candidate_edges < 1) fail("hypothesis_candidate_edges must be >= 1");

  const RecognitionOptions& r = o.recognition;
  if (!(r.closure_min_evidence >= 0.0 && r.closure_min_evidence <= 1.0)) {
    fail("recognition.closure_min_evidence must be in [0, 1]");
  }
  if (!(r.observation_window_m >= 0.0 && std::isfinite(r.observation_window_m))) {
    fail("recognition.observation_window_m must be finite and >= 0");
  }

  const NewPlaceOptions& n = o.new_place;
  if (n.log_offset && !std::isfinite(*n.log_offset)) fail("new_place.log_offset must be finite");
  if (!(n.leave_probability > 0.0 && n.leave_probability < 1.0)) fail("new_place.leave_probability must be in (0, 1)");
  if (!(n.stay_fraction >= 0.0 && n.stay_fraction <= 1.0)) fail("new_place.stay_fraction must be in [0, 1]");
  if (!(n.stay_relative_offset >= 0.0 && n.stay_relative_offset < 1.0)) {
    fail("new_place.stay_relative_offset must be in [0, 1)");
  }
  if (n.motion_sigma && !IsValidSigma(*n.motion_sigma)) fail("new_place.motion_sigma must be finite and > 0");

  if (!(o.gate.base_m >= 0.0 && o.gate.fraction >= 0.0)) fail("gate.base_m and gate.fraction must be >= 0");

  const InferenceOptions& i = o.inference;
  if (!(i.local_validation_m > 0.0)) fail("inference.local_validation_m (d_loc) must be > 0");
  if (!(i.total_validation_m > 0.0)) fail("inference.total_validation_m (d_tot) must be > 0");
  if (!(i.total_path_retries >= 0 && i.total_path_retries <= 100)) {
    fail("inference.total_path_retries must be in [0, 100]");
  }
  if (!(i.particle_factor >= 1 && i.particle_factor <= 100)) fail("inference.particle_factor must be in [1, 100]");
  if (i.motion_sigma && !IsValidSigma(*i.motion_sigma)) fail("inference.motion_sigma must be finite and > 0");
}

CatGraphOptions CatGraphOptions::Paper() {
  CatGraphOptions o;
  o.motion_sigma = Eigen::Vector3d(0.05, 0.05, 0.005);
  o.recognition = {.closure_min_evidence = 0.0, .forward_camera = false, .observation_window_m = 0.0};
  // One prior for new place whether or not the robot is on the map, and one
  // likelihood: Eq 6 as written, weighed by Q.
  o.new_place = {.log_offset = 0.0,
                 .leave_probability = o.new_place_prior,
                 .stay_fraction = 1.0,
                 .stay_relative_offset = 0.0,
                 .hold_after_closure = false,
                 .motion_sigma = std::nullopt};
  o.gate.enabled = false;
  o.inference = {.enabled = true,
                 .local_validation_m = 2.0,
                 .total_validation_m = 1.0,
                 .total_path_retries = 0,
                 .seed_local = false,
                 .particle_factor = 1,
                 .motion_sigma = std::nullopt};
  return o;
}

double OdometricGateRadius(const CatGraphOptions& options, double path_since_m) {
  if (!options.gate.enabled) return std::numeric_limits<double>::infinity();
  return options.gate.base_m + options.gate.fraction * path_since_m;
}

}  // namespace catgraph
