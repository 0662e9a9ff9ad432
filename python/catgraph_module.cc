// Python bindings (pybind11): the module catgraph._catgraph, which
// python/catgraph/__init__.py re-exports as `catgraph`. Poses and matrices
// cross as numpy arrays; ids as ints; kinds, methods and formats as the
// strings the command line uses. Errors: FileError becomes
// catgraph.FileError (an OSError), std::invalid_argument ValueError.
// docs/python.md.
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "backend/chi_square.h"
#include "backend/evaluation.h"
#include "backend/factors.h"
#include "backend/graph/pose_graph.h"
#include "backend/graph/trajectory.h"
#include "backend/io/closure_labels.h"
#include "backend/io/dataset.h"
#include "backend/io/file_error.h"
#include "backend/io/graph_io.h"
#include "backend/io/image_file.h"
#include "backend/io/trajectory_io.h"
#include "backend/optimizer.h"
#include "backend/pose_graph_optimizer.h"
#include "frontend/fabmap.h"
#include "frontend/localization.h"
#include "mapping/mapper.h"
#include "simulation/dataset_import.h"
#include "simulation/manhattan_world.h"
#include "simulation/office_simulator.h"
#include "simulation/outlier_injection.h"
#include "simulation/scenario.h"

namespace py = pybind11;

namespace catgraph {
namespace {

template <typename Enum>
Enum Parse(std::optional<Enum> value, const std::string& text, const char* what) {
  if (!value) throw std::invalid_argument("unknown " + std::string(what) + " '" + text + "'");
  return *value;
}

ClosureKind KindFromString(const std::string& text) {
  return Parse(ClosureKindFromString(text), text, "closure kind (odometry, visual, inferred, injected, unknown)");
}

// A pose graph of either dimension, as Python sees it.
struct PyPoseGraph {
  AnyPoseGraph graph;

  int dimension() const { return graph.index() == 0 ? 2 : 3; }
};

// A trajectory of either dimension (a struct, so that pybind11's variant
// caster does not take it apart).
struct PyTrajectory {
  AnyTrajectory trajectory;
};

// One constraint, copied out of a graph.
struct PyConstraint {
  std::int64_t id = 0, from = 0, to = 0;
  std::string kind;
  py::object measurement;  // Pose2 or Pose3
  Eigen::MatrixXd information;
  bool loop_closure = false;
  bool accepted = true;
  std::optional<double> weight;        // the robust solve's, when it left a decision
  std::optional<double> switch_value;  // a switchable constraint's switch
  std::vector<std::int64_t> parents;
};

template <typename PoseT>
PyConstraint ToPython(const PoseGraph<PoseT>& g, const Constraint<PoseT>& c) {
  PyConstraint out;
  out.id = c.id.value();
  out.from = c.from.value();
  out.to = c.to.value();
  out.kind = std::string(ToString(c.kind));
  out.measurement = py::cast(c.measurement.mean);
  out.information = c.measurement.information;
  out.loop_closure = !c.IsBetweenConsecutivePoses();
  out.accepted = g.IsAccepted(c);
  if (c.decision) out.weight = c.decision->weight;
  if (c.switch_id) out.switch_value = g.switches.at(*c.switch_id).value;
  for (const ClosureId parent : c.provenance.parents) out.parents.push_back(parent.value());
  return out;
}

// Rows [x, y, theta] or [tx, ty, tz, qx, qy, qz, qw] (g2o's order).
Eigen::VectorXd Row(const Pose2& p) { return Eigen::Vector3d(p.x(), p.y(), p.theta()); }
Eigen::VectorXd Row(const Pose3& p) {
  Eigen::VectorXd r(7);
  r << p.translation(), p.rotation().x(), p.rotation().y(), p.rotation().z(), p.rotation().w();
  return r;
}

template <typename PoseT>
Eigen::MatrixXd PoseRows(const std::map<PoseId, PoseT>& poses) {
  Eigen::MatrixXd rows(static_cast<Eigen::Index>(poses.size()), PoseT::kTangentDim == 3 ? 3 : 7);
  Eigen::Index r = 0;
  for (const auto& [id, pose] : poses) rows.row(r++) = Row(pose).transpose();
  return rows;
}

template <typename PoseT>
InformationMatrix<PoseT> InformationOr(const std::optional<Eigen::MatrixXd>& information) {
  if (!information) return InformationMatrix<PoseT>::Identity();
  if (information->rows() != PoseT::kTangentDim || information->cols() != PoseT::kTangentDim) {
    throw std::invalid_argument("information: expected a " + std::to_string(PoseT::kTangentDim) + " x " +
                                std::to_string(PoseT::kTangentDim) + " matrix");
  }
  return *information;
}

Pose3 Pose3From(const Eigen::Vector3d& translation, const Eigen::Vector4d& quaternion_xyzw) {
  const Eigen::Quaterniond q(quaternion_xyzw[3], quaternion_xyzw[0], quaternion_xyzw[1], quaternion_xyzw[2]);
  if (!(q.norm() > 0.0) || !q.coeffs().allFinite()) throw std::invalid_argument("quaternion: expected a non-zero (x, y, z, w)");
  return Pose3(translation, q);
}

AnyTrajectory TrajectoryFrom(const py::object& source) {
  if (py::isinstance<PyPoseGraph>(source)) return TrajectoryOf(source.cast<const PyPoseGraph&>().graph);
  return source.cast<const PyTrajectory&>().trajectory;
}

// Dataset poses as rows [t, x, y, theta].
Eigen::MatrixXd TimedRows(const std::vector<TimedPose2>& poses) {
  Eigen::MatrixXd rows(static_cast<Eigen::Index>(poses.size()), 4);
  for (std::size_t i = 0; i < poses.size(); ++i) {
    rows.row(static_cast<Eigen::Index>(i)) << poses[i].timestamp_s, poses[i].pose.x(), poses[i].pose.y(),
        poses[i].pose.theta();
  }
  return rows;
}

void BindPoses(py::module_& m) {
  py::class_<Pose2>(m, "Pose2", "A rigid transform in the plane: (x, y, theta), theta in radians.")
      .def(py::init<double, double, double>(), py::arg("x") = 0.0, py::arg("y") = 0.0, py::arg("theta") = 0.0)
      .def_property_readonly("x", &Pose2::x)
      .def_property_readonly("y", &Pose2::y)
      .def_property_readonly("theta", &Pose2::theta)
      .def("inverse", &Pose2::Inverse)
      .def("between", &Pose2::Between, "this.inverse() * other")
      .def("__mul__", [](const Pose2& a, const Pose2& b) { return a * b; })
      .def("vector", [](const Pose2& p) { return Eigen::Vector3d(p.x(), p.y(), p.theta()); })
      .def("__repr__", [](const Pose2& p) {
        std::ostringstream s;
        s << "Pose2(" << p.x() << ", " << p.y() << ", " << p.theta() << ")";
        return s.str();
      });
  py::class_<Pose3>(m, "Pose3", "A rigid transform in space: a translation and a unit quaternion (x, y, z, w).")
      .def(py::init(&Pose3From), py::arg("translation"), py::arg("quaternion"))
      .def(py::init([] { return Pose3(); }))
      .def_property_readonly("translation", [](const Pose3& p) { return Eigen::Vector3d(p.translation()); })
      .def_property_readonly("quaternion", [](const Pose3& p) { return Eigen::Vector4d(p.rotation().coeffs()); },
                             "(x, y, z, w)")
      .def("inverse", &Pose3::Inverse)
      .def("between", &Pose3::Between, "this.inverse() * other")
      .def("__mul__", [](const Pose3& a, const Pose3& b) { return a * b; })
      .def("vector", [](const Pose3& p) { return Row(p); }, "[tx, ty, tz, qx, qy, qz, qw]")
      .def("__repr__", [](const Pose3& p) {
        std::ostringstream s;
        const auto q = p.rotation();
        s << "Pose3([" << p.translation().transpose() << "], [" << q.x() << " " << q.y() << " " << q.z() << " "
          << q.w() << "])";
        return s.str();
      });
}

void BindGraph(py::module_& m) {
  py::class_<PyConstraint>(m, "Constraint", "One constraint of a pose graph, copied out of it.")
      .def_readonly("id", &PyConstraint::id)
      .def_readonly("from_id", &PyConstraint::from)
      .def_readonly("to_id", &PyConstraint::to)
      .def_readonly("kind", &PyConstraint::kind, "odometry, visual, inferred, injected or unknown")
      .def_readonly("measurement", &PyConstraint::measurement)
      .def_readonly("information", &PyConstraint::information)
      .def_readonly("loop_closure", &PyConstraint::loop_closure, "not between consecutive pose ids")
      .def_readonly("accepted", &PyConstraint::accepted,
                    "the robust solve's decision where it left one, else its switch above 0.5, else True")
      .def_readonly("weight", &PyConstraint::weight, "the robust solve's weight, or None")
      .def_readonly("switch", &PyConstraint::switch_value, "the switch's value, or None")
      .def_readonly("parents", &PyConstraint::parents, "the closures an inferred closure hangs from");

  py::class_<PyPoseGraph>(m, "PoseGraph", "A 2D or 3D pose graph: vertices with poses, constraints, switches.")
      .def(py::init([](int dimension) {
             if (dimension == 2) return PyPoseGraph{PoseGraph2{}};
             if (dimension == 3) return PyPoseGraph{PoseGraph3{}};
             throw std::invalid_argument("dimension: expected 2 or 3");
           }),
           py::arg("dimension") = 2)
      .def_property_readonly("dimension", &PyPoseGraph::dimension)
      .def_property_readonly("num_vertices",
                             [](const PyPoseGraph& g) {
                               return std::visit([](const auto& x) { return x.vertices.size(); }, g.graph);
                             })
      .def_property_readonly("num_constraints",
                             [](const PyPoseGraph& g) {
                               return std::visit([](const auto& x) { return x.constraints.size(); }, g.graph);
                             })
      .def("vertex_ids",
           [](const PyPoseGraph& g) {
             std::vector<std::int64_t> ids;
             std::visit([&](const auto& x) { for (const auto& [id, v] : x.vertices) ids.push_back(id.value()); },
                        g.graph);
             return ids;
           })
      .def("poses", [](const PyPoseGraph& g) { return std::visit([](const auto& x) { return PoseRows(TrajectoryOf(x)); }, g.graph); },
           "Rows [x, y, theta] (2D) or [tx, ty, tz, qx, qy, qz, qw] (3D), in vertex_ids() order.")
      .def("pose",
           [](const PyPoseGraph& g, std::int64_t id) -> py::object {
             return std::visit(
                 [&](const auto& x) -> py::object {
                   const auto it = x.vertices.find(PoseId(id));
                   if (it == x.vertices.end() || !it->second.pose) return py::none();
                   return py::cast(*it->second.pose);
                 },
                 g.graph);
           },
           py::arg("id"), "The vertex's pose, or None")
      .def("add_vertex",
           [](PyPoseGraph& g, std::int64_t id, const py::object& pose, bool fixed) {
             std::visit(
                 [&](auto& x) {
                   using PoseT = typename std::decay_t<decltype(x)>::Pose;
                   x.vertices[PoseId(id)] = Vertex<PoseT>{PoseId(id), pose.cast<PoseT>(), fixed};
                 },
                 g.graph);
           },
           py::arg("id"), py::arg("pose"), py::arg("fixed") = false)
      .def("add_constraint",
           [](PyPoseGraph& g, std::int64_t from, std::int64_t to, const py::object& measurement,
              const std::optional<Eigen::MatrixXd>& information, const std::string& kind) {
             return std::visit(
                 [&](auto& x) {
                   using PoseT = typename std::decay_t<decltype(x)>::Pose;
                   for (const std::int64_t id : {from, to}) {
                     if (!x.vertices.contains(PoseId(id))) {
                       throw std::invalid_argument("pose " + std::to_string(id) + " is not a vertex; add it first");
                     }
                   }
                   Constraint<PoseT> c;
                   c.id = x.NextClosureId();
                   c.from = PoseId(from);
                   c.to = PoseId(to);
                   c.measurement = {measurement.cast<PoseT>(), InformationOr<PoseT>(information)};
                   c.kind = KindFromString(kind);
                   x.constraints.push_back(c);
                   return c.id.value();
                 },
                 g.graph);
           },
           py::arg("from_id"), py::arg("to_id"), py::arg("measurement"), py::arg("information") = py::none(),
           py::arg("kind") = "unknown", "Adds a constraint (identity information by default); returns its id.")
      .def("constraints",
           [](const PyPoseGraph& g) {
             std::vector<PyConstraint> out;
             std::visit([&](const auto& x) { for (const auto& c : x.constraints) out.push_back(ToPython(x, c)); },
                        g.graph);
             return out;
           })
      .def("loop_closures",
           [](const PyPoseGraph& g) {
             std::vector<PyConstraint> out;
             std::visit(
                 [&](const auto& x) {
                   for (const auto& c : x.constraints) {
                     if (!c.IsBetweenConsecutivePoses()) out.push_back(ToPython(x, c));
                   }
                 },
                 g.graph);
             return out;
           })
      .def("write_g2o", [](const PyPoseGraph& g, const std::filesystem::path& path) { WriteG2oFile(g.graph, path); },
           py::arg("path"), "Writes g2o text atomically, with every closure's kind, provenance and decision.")
      .def("copy", [](const PyPoseGraph& g) { return g; });

  m.def("read_graph",
        [](const std::filesystem::path& path, const std::string& format) {
          ReadGraphOptions options;
          options.format = Parse(GraphFormatFromString(format), format, "graph format (auto, g2o, toro, isam)");
          return PyPoseGraph{ReadGraphFile(path, options).graph};
        },
        py::arg("path"), py::arg("format") = "auto", "Reads a g2o, TORO or iSAM file.");
}

// Calls `f` with `pose` as the Pose2 or Pose3 it holds (a TypeError for
// anything else).
template <typename F>
void WithPose(const py::object& pose, F f) {
  if (py::isinstance<Pose2>(pose)) {
    f(pose.cast<Pose2>());
  } else {
    f(pose.cast<Pose3>());
  }
}

void BindFactorGraph(py::module_& m) {
  py::class_<Summary>(m, "Summary", "How a solve ended.")
      .def_property_readonly("usable", &Summary::IsUsable, "converged, or stopped at the limit with a finite cost")
      .def_readonly("message", &Summary::message)
      .def_readonly("iterations", &Summary::iterations)
      .def_readonly("initial_cost", &Summary::initial_cost)
      .def_readonly("final_cost", &Summary::final_cost)
      .def_readonly("time_s", &Summary::time_s)
      .def("brief_report", &Summary::BriefReport)
      .def("__repr__", &Summary::BriefReport);

  py::class_<Values>(m, "Values", "Variables under typed keys: poses by pose id, switches by switch id.")
      .def(py::init<>())
      .def("insert_pose", [](Values& v, std::int64_t id, const Pose2& p) { v.Insert(PoseId(id), p); }, py::arg("id"),
           py::arg("pose"))
      .def("insert_pose", [](Values& v, std::int64_t id, const Pose3& p) { v.Insert(PoseId(id), p); }, py::arg("id"),
           py::arg("pose"))
      .def("insert_switch", [](Values& v, std::int64_t id, double s) { v.Insert(SwitchId(id), s); }, py::arg("id"),
           py::arg("value") = 1.0)
      .def("pose2", [](const Values& v, std::int64_t id) { return v.AtPose2(PoseId(id)); }, py::arg("id"))
      .def("pose3", [](const Values& v, std::int64_t id) { return v.AtPose3(PoseId(id)); }, py::arg("id"))
      .def("switch", [](const Values& v, std::int64_t id) { return v.AtSwitch(SwitchId(id)); }, py::arg("id"))
      .def("__len__", &Values::size);

  py::class_<FactorGraph>(m, "FactorGraph", "Factors over Values, GTSAM-style, solved by Ceres.")
      .def(py::init<>())
      .def("add_between",
           [](FactorGraph& g, std::int64_t from, std::int64_t to, const py::object& z,
              const std::optional<Eigen::MatrixXd>& information) {
             WithPose(z, [&](const auto& pose) {
               using PoseT = std::decay_t<decltype(pose)>;
               g.Emplace<BetweenFactor<PoseT>>(PoseId(from), PoseId(to),
                                               RelativePoseMeasurement<PoseT>{pose, InformationOr<PoseT>(information)});
             });
           },
           py::arg("from_id"), py::arg("to_id"), py::arg("measurement"), py::arg("information") = py::none())
      .def("add_switchable_between",
           [](FactorGraph& g, std::int64_t from, std::int64_t to, std::int64_t switch_id, const py::object& z,
              const std::optional<Eigen::MatrixXd>& information) {
             WithPose(z, [&](const auto& pose) {
               using PoseT = std::decay_t<decltype(pose)>;
               g.Emplace<SwitchableBetweenFactor<PoseT>>(
                   PoseId(from), PoseId(to), SwitchId(switch_id),
                   RelativePoseMeasurement<PoseT>{pose, InformationOr<PoseT>(information)});
             });
           },
           py::arg("from_id"), py::arg("to_id"), py::arg("switch_id"), py::arg("measurement"),
           py::arg("information") = py::none(),
           "Suenderhauf & Protzel's switchable constraint: the residual scaled by the switch in [0, 1].")
      .def("add_switch_prior",
           [](FactorGraph& g, std::int64_t switch_id, double mean, double information) {
             if (!(information > 0.0)) throw std::invalid_argument("information: expected > 0");
             g.Emplace<SwitchPriorFactor>(SwitchId(switch_id), SwitchPrior{mean, information});
           },
           py::arg("switch_id"), py::arg("mean") = 1.0, py::arg("information") = 1.0)
      .def("add_prior",
           [](FactorGraph& g, std::int64_t id, const py::object& pose, const std::optional<Eigen::MatrixXd>& information) {
             WithPose(pose, [&](const auto& prior) {
               using PoseT = std::decay_t<decltype(prior)>;
               g.Emplace<PriorFactor<PoseT>>(PoseId(id), prior, InformationOr<PoseT>(information));
             });
           },
           py::arg("id"), py::arg("pose"), py::arg("information") = py::none())
      .def("set_constant_pose", [](FactorGraph& g, std::int64_t id) { g.SetConstant(PoseKey(PoseId(id))); },
           py::arg("id"), "Holds a pose fixed (the gauge)")
      .def("__len__", &FactorGraph::size);

  m.def("optimize_factor_graph",
        [](const FactorGraph& graph, const Values& initial, int max_iterations) {
          OptimizerOptions options;
          options.max_iterations = max_iterations;
          Validate(options);
          OptimizationResult result;
          {
            py::gil_scoped_release release;
            result = Optimize(graph, initial, options);
          }
          return py::make_tuple(result.values, result.summary);
        },
        py::arg("graph"), py::arg("initial"), py::arg("max_iterations") = 200,
        "Levenberg-Marquardt on Ceres; returns (values, summary). A failed solve is a summary that is not usable.");
  m.def("chi_square_quantile", &ChiSquareQuantile, py::arg("dof"), py::arg("probability"),
        "The chi2 quantile: the switch-prior information that makes the switch a chi2 gate.");
}

void BindOptimizer(py::module_& m) {
  py::class_<ClosureDecision>(m, "ClosureDecision", "What the robust solve decided about one loop closure.")
      .def_property_readonly("id", [](const ClosureDecision& d) { return d.id.value(); })
      .def_property_readonly("from_id", [](const ClosureDecision& d) { return d.from.value(); })
      .def_property_readonly("to_id", [](const ClosureDecision& d) { return d.to.value(); })
      .def_property_readonly("kind", [](const ClosureDecision& d) { return std::string(ToString(d.kind)); })
      .def_readonly("weight", &ClosureDecision::weight)
      .def_readonly("accepted", &ClosureDecision::accepted)
      .def_readonly("readmitted", &ClosureDecision::readmitted);

  py::class_<StageTime>(m, "StageTime", "One stage of a robust solve: its wall-clock time and iterations.")
      .def_readonly("stage", &StageTime::stage)
      .def_readonly("time_s", &StageTime::time_s)
      .def_readonly("iterations", &StageTime::iterations)
      .def("__repr__", [](const StageTime& s) {
        return "StageTime(" + s.stage + ", " + std::to_string(s.time_s) + " s, " + std::to_string(s.iterations) +
               " iterations)";
      });

  py::class_<PoseGraphOptimization>(m, "Optimization", "A robust solve: the corrected graph and every decision.")
      .def_property_readonly("graph", [](const PoseGraphOptimization& o) { return PyPoseGraph{o.graph}; })
      .def_readonly("closures", &PoseGraphOptimization::closures)
      .def_readonly("accepted", &PoseGraphOptimization::accepted)
      .def_readonly("rejected", &PoseGraphOptimization::rejected)
      .def_readonly("readmitted", &PoseGraphOptimization::readmitted)
      .def_readonly("summary", &PoseGraphOptimization::summary, "the robust solve")
      .def_readonly("chi2", &PoseGraphOptimization::chi2)
      .def_property_readonly("initial_guess",
                             [](const PoseGraphOptimization& o) { return std::string(ToString(o.initial_guess)); })
      .def_property_readonly("time_s", &PoseGraphOptimization::TotalTimeS, "every solve and test together")
      .def_readonly("stages", &PoseGraphOptimization::stages, "the stages that ran, in order")
      .def_property_readonly("wall_time_s", &PoseGraphOptimization::WallTimeS, "the stages' times together");

  m.def(
      "optimize",
      [](const PyPoseGraph& graph, const std::string& method, const std::string& initial_guess,
         double switch_gate_probability, bool refine, bool readmit, bool estimate_noise_scale, bool narrow_gate,
         int num_threads) {
        PoseGraphOptimizerOptions options;
        options.method = Parse(RobustMethodFromString(method), method, "method (none, switchable, dcs, cauchy, huber, gnc)");
        options.initial_guess =
            Parse(InitialGuessFromString(initial_guess), initial_guess, "initial guess (auto, file, spanning-tree, chordal)");
        options.gate.probability = switch_gate_probability;
        options.refinement.enabled = refine;
        options.readmission.enabled = readmit && refine;
        options.gate.estimate_noise_scale = estimate_noise_scale;
        options.gate.narrow = narrow_gate && estimate_noise_scale;
        options.solver.num_threads = num_threads;
        py::gil_scoped_release release;
        return OptimizePoseGraph(graph.graph, options);
      },
      py::arg("graph"), py::arg("method") = "switchable", py::arg("initial_guess") = "auto",
      py::arg("switch_gate_probability") = 0.999, py::arg("refine") = true, py::arg("readmit") = true,
      py::arg("estimate_noise_scale") = true, py::arg("narrow_gate") = true, py::arg("num_threads") = 1,
      "Robust optimisation as `catgraph optimize`: the defaults need no tuning (docs/backend.md).");
}

void BindEvaluation(py::module_& m) {
  py::class_<PyTrajectory>(m, "Trajectory", "Poses by id (2D or 3D), as read from a trajectory file.")
      .def_property_readonly("dimension", [](const PyTrajectory& t) { return t.trajectory.index() == 0 ? 2 : 3; })
      .def("ids",
           [](const PyTrajectory& t) {
             std::vector<std::int64_t> ids;
             std::visit([&](const auto& x) { for (const auto& [id, p] : x) ids.push_back(id.value()); }, t.trajectory);
             return ids;
           })
      .def("poses",
           [](const PyTrajectory& t) { return std::visit([](const auto& x) { return PoseRows(x); }, t.trajectory); },
           "Rows as PoseGraph.poses()")
      .def("__len__",
           [](const PyTrajectory& t) { return std::visit([](const auto& x) { return x.size(); }, t.trajectory); });
  m.def("read_trajectory",
        [](const std::filesystem::path& path, const std::string& format) {
          return PyTrajectory{ReadTrajectoryFile(
              path, Parse(TrajectoryFormatFromString(format), format, "trajectory format (auto, graph, poses, tum)"))};
        },
        py::arg("path"), py::arg("format") = "auto", "A pose graph's poses, a pose list or a TUM file.");
  m.def("write_tum",
        [](const py::object& source, const std::filesystem::path& path) { WriteTumFile(TrajectoryFrom(source), path); },
        py::arg("trajectory"), py::arg("path"), "TUM text (timestamp = pose id), for evo.");

  py::class_<ErrorStatistics>(m, "ErrorStatistics")
      .def_readonly("count", &ErrorStatistics::count)
      .def_readonly("rmse", &ErrorStatistics::rmse)
      .def_readonly("mean", &ErrorStatistics::mean)
      .def_readonly("median", &ErrorStatistics::median)
      .def_readonly("max", &ErrorStatistics::max);
  py::class_<TrajectoryEvaluation>(m, "TrajectoryEvaluation")
      .def_readonly("poses", &TrajectoryEvaluation::poses)
      .def_readonly("ate_m", &TrajectoryEvaluation::ate_m, "after a rigid alignment without scale")
      .def_readonly("rmse_anchored_m", &TrajectoryEvaluation::rmse_anchored_m, "pose 0 on its true pose")
      .def_readonly("rpe_translation_m", &TrajectoryEvaluation::rpe_translation_m)
      .def_readonly("rpe_rotation_rad", &TrajectoryEvaluation::rpe_rotation_rad);
  m.def("evaluate_trajectory",
        [](const py::object& estimate, const py::object& truth) {
          return EvaluateTrajectory(TrajectoryFrom(estimate), TrajectoryFrom(truth));
        },
        py::arg("estimate"), py::arg("truth"), "ATE, anchored RMSE and RPE (PoseGraph or Trajectory arguments).");

  py::class_<ClosureLabel>(m, "ClosureLabel", "Whether a loop closure is an outlier (written by inject).")
      .def_property_readonly("id", [](const ClosureLabel& l) { return l.id.value(); })
      .def_property_readonly("from_id", [](const ClosureLabel& l) { return l.from.value(); })
      .def_property_readonly("to_id", [](const ClosureLabel& l) { return l.to.value(); })
      .def_readonly("outlier", &ClosureLabel::outlier)
      .def_property_readonly("kind", [](const ClosureLabel& l) { return std::string(ToString(l.kind)); })
      .def_readonly("group", &ClosureLabel::group);
  m.def("read_closure_labels", [](const std::filesystem::path& path) { return ReadClosureLabelsFile(path); },
        py::arg("path"));

  py::class_<ClosureScores>(m, "ClosureScores")
      .def_readonly("true_positives", &ClosureScores::true_positives)
      .def_readonly("false_positives", &ClosureScores::false_positives)
      .def_readonly("true_negatives", &ClosureScores::true_negatives)
      .def_readonly("false_negatives", &ClosureScores::false_negatives)
      .def_readonly("precision", &ClosureScores::precision)
      .def_readonly("recall", &ClosureScores::recall)
      .def_readonly("f1", &ClosureScores::f1);
  m.def("score_closures",
        [](const PyPoseGraph& graph, const std::vector<ClosureLabel>& labels) {
          if (const auto mismatch = FindLabelMismatch(graph.graph, labels)) throw std::invalid_argument(mismatch->message);
          return ScoreClosures(ClosureOutcomesOf(graph.graph), labels);
        },
        py::arg("graph"), py::arg("labels"),
        "Precision and recall of the graph's accepted loop closures (their decisions, else switches) against labels.");
}

void BindSimulation(py::module_& m) {
  m.def(
      "simulate_manhattan",
      [](int poses, std::uint64_t seed) {
        ManhattanWorldOptions options;
        options.num_poses = poses;
        options.seed = seed;
        Validate(options);
        SimulatedPoseGraph2 world = SimulateManhattanWorld(options);
        return py::make_tuple(PyPoseGraph{std::move(world.graph)}, PyPoseGraph{std::move(world.truth)});
      },
      py::arg("poses") = 500, py::arg("seed") = 1,
      "A 2D Manhattan world as `catgraph generate-graph`: (noisy graph, truth).");
  m.def(
      "inject_outliers",
      [](PyPoseGraph& graph, int count, const std::string& policy, int group_size, int local_window,
         std::uint64_t seed) {
        OutlierOptions options;
        options.count = count;
        options.policy = Parse(OutlierPolicyFromString(policy), policy, "policy (random, local, random-grouped, local-grouped)");
        options.group_size = group_size;
        options.local_window = local_window;
        options.seed = seed;
        Validate(options);
        const std::vector<InjectedClosure> injected = InjectOutliers(graph.graph, options);
        return LabelClosures(graph.graph, injected);
      },
      py::arg("graph"), py::arg("count"), py::arg("policy") = "random", py::arg("group_size") = 0,
      py::arg("local_window") = 20, py::arg("seed") = 1,
      "Adds `count` false loop closures to the graph in place, as `catgraph inject`; returns every closure's label.");

  py::class_<DatasetFrame>(m, "DatasetFrame")
      .def_readonly("timestamp_s", &DatasetFrame::timestamp_s)
      .def_readonly("image", &DatasetFrame::image, "relative to the dataset folder")
      .def_readonly("traversal", &DatasetFrame::traversal)
      .def_readonly("changed", &DatasetFrame::changed);
  py::class_<Dataset>(m, "Dataset", "A dataset folder (docs/dataset-format.md).")
      .def_readonly("root", &Dataset::root)
      .def_readonly("frames", &Dataset::frames)
      .def_property_readonly("odometry", [](const Dataset& d) { return TimedRows(d.odometry); }, "rows [t, x, y, theta]")
      .def_property_readonly("ground_truth", [](const Dataset& d) { return TimedRows(d.ground_truth); },
                             "rows [t, x, y, theta]; empty when the dataset has none")
      .def("image_path", &Dataset::ImagePath, py::arg("frame"));
  m.def("read_dataset", &ReadDataset, py::arg("path"));
  m.def(
      "read_image",
      [](const std::filesystem::path& path) {
        const cv::Mat image = ReadImage(path);
        py::array_t<std::uint8_t> out({image.rows, image.cols, 3});
        for (int r = 0; r < image.rows; ++r) {
          std::memcpy(out.mutable_data(r), image.ptr(r), static_cast<std::size_t>(image.cols) * 3);
        }
        return out;
      },
      py::arg("path"), "An image as an H x W x 3 uint8 array, BGR (OpenCV's order).");
  m.def(
      "simulate",
      [](const std::string& scenario, const std::filesystem::path& directory, std::size_t max_frames,
         std::optional<std::uint64_t> seed) {
        SimulationOptions options;
        options.max_frames = max_frames;
        options.seed = seed;
        const Scenario s = LoadScenario(scenario);
        py::gil_scoped_release release;
        return SimulateDataset(s, directory, options).frames;
      },
      py::arg("scenario"), py::arg("directory"), py::arg("max_frames") = 0, py::arg("seed") = py::none(),
      "Renders a scenario (a built-in name or a YAML file) into a dataset folder, as `catgraph simulate` without "
      "its staging; returns the number of frames.");
  m.def(
      "import_dataset",
      [](const std::string& layout, const std::filesystem::path& source, const std::filesystem::path& directory,
         const std::optional<std::filesystem::path>& times, const std::optional<std::filesystem::path>& odometry,
         const std::optional<std::filesystem::path>& poses, double traversal_gap_s, std::uint64_t seed) {
        const std::optional<ImportLayout> kind = ImportLayoutFromString(layout);
        if (!kind) throw std::invalid_argument("layout: expected folder, kitti or tum, not '" + layout + "'");
        ImportOptions options;
        options.times = times.value_or(std::filesystem::path());
        options.odometry = odometry.value_or(std::filesystem::path());
        options.poses = poses.value_or(std::filesystem::path());
        options.traversal_gap_s = traversal_gap_s;
        options.seed = seed;
        ImportSummary s;
        {
          py::gil_scoped_release release;
          s = ImportDataset(*kind, source, directory, options);
        }
        return py::make_tuple(s.frames, s.left_out, s.traversals, s.synthetic_odometry);
      },
      py::arg("layout"), py::arg("source"), py::arg("directory"), py::arg("times") = py::none(),
      py::arg("odometry") = py::none(), py::arg("poses") = py::none(), py::arg("traversal_gap_s") = 5.0,
      py::arg("seed") = 1,
      "Imports a recording (layout 'folder', 'kitti' or 'tum') into a dataset folder, as `catgraph import` "
      "without its staging (docs/import.md); returns (frames, left_out, traversals, synthetic_odometry).");
}

void BindFrontEnd(py::module_& m) {
  py::class_<LoopClosure>(m, "LoopClosure", "A loop closure of the front end.")
      .def_readonly("id", &LoopClosure::id)
      .def_property_readonly("kind", [](const LoopClosure& c) { return std::string(ToString(c.kind)); })
      .def_readonly("frame", &LoopClosure::frame)
      .def_readonly("matched_frame", &LoopClosure::matched_frame)
      .def_readonly("relative_pose", &LoopClosure::T_frame_matched, "the matched frame's pose in this frame's")
      .def_readonly("error_m", &LoopClosure::error_m, "against ground truth; nan without it")
      .def_readonly("parents", &LoopClosure::parents);
  py::class_<LocalizationResult>(m, "Localization", "CAT-Graph and CAT-Graph+ over a dataset.")
      .def_readonly("closures", &LocalizationResult::closures)
      .def_property_readonly("graph", [](const LocalizationResult& r) { return PyPoseGraph{r.graph}; },
                             "odometry edges and the closures, for optimize()");
  m.def(
      "localize",
      [](const Dataset& dataset, bool infer) {
        LocalizationOptions options;
        options.filter.inference.enabled = infer;
        py::gil_scoped_release release;
        const HolisticFrontEnd front_end = PrepareHolistic(dataset, {}, options);
        return Localize(dataset, front_end.observations, *front_end.model, options);
      },
      py::arg("dataset"), py::arg("odometric_inference") = true,
      "CAT-Graph with the holistic observation model calibrated on the first traversal, and CAT-Graph+'s "
      "inferred closures unless odometric_inference is False.");
}

// An image from Python (H x W x 3 BGR or H x W grey, uint8) as a cv::Mat
// over the array's memory, which must outlive it.
cv::Mat ImageOf(const py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>& image) {
  if (image.ndim() == 2) {
    return cv::Mat(static_cast<int>(image.shape(0)), static_cast<int>(image.shape(1)), CV_8UC1,
                   const_cast<std::uint8_t*>(image.data()));
  }
  if (image.ndim() == 3 && image.shape(2) == 3) {
    return cv::Mat(static_cast<int>(image.shape(0)), static_cast<int>(image.shape(1)), CV_8UC3,
                   const_cast<std::uint8_t*>(image.data()));
  }
  throw std::invalid_argument("an image must be an H x W x 3 (BGR) or H x W uint8 array");
}

// The online Mapper over FAB-MAP on a vocabulary, which it keeps alive.
struct PyMapper {
  std::shared_ptr<const Vocabulary> vocabulary;
  std::unique_ptr<FabMapModel> model;
  std::unique_ptr<mapping::Mapper> mapper;
};

void BindMapping(py::module_& m) {
  py::class_<Vocabulary, std::shared_ptr<Vocabulary>>(m, "Vocabulary", "A visual vocabulary with its Chow-Liu tree.")
      .def_property_readonly("size", &Vocabulary::size, "words")
      .def_static("load", &Vocabulary::Load, py::arg("path"), "as `catgraph vocabulary` writes it")
      .def("save", &Vocabulary::Save, py::arg("path"));
  m.def(
      "train_map_vocabulary",
      [](const Dataset& dataset, int words, int every) {
        VocabularyOptions options;
        options.words = words;
        py::gil_scoped_release release;
        return std::make_shared<Vocabulary>(TrainMapVocabulary(dataset, options, every).vocabulary);
      },
      py::arg("dataset"), py::arg("words") = 1000, py::arg("every") = 0,
      "The default vocabulary: SIFT words trained on the dataset's first traversal (every `every`-th frame, or "
      "about 200 frames when 0), as `catgraph map` makes it.");
  py::class_<mapping::FrameResult>(m, "FrameResult", "What one frame brought (Mapper.add_frame).")
      .def_property_readonly("frame", [](const mapping::FrameResult& r) { return r.localization.frame; })
      .def_property_readonly("new_place_probability",
                             [](const mapping::FrameResult& r) { return r.localization.new_place_probability; })
      .def_property_readonly("matched_frame", [](const mapping::FrameResult& r) {
        return r.localization.closure ? py::object(py::int_(r.localization.matched_frame)) : py::object(py::none());
      }, "the frame a visual closure matched; None without one")
      .def_readonly("closures", &mapping::FrameResult::closures, "made at this frame, with their parents")
      .def_property_readonly("solved", [](const mapping::FrameResult& r) { return r.solve.has_value(); })
      .def_property_readonly("solve_time_s",
                             [](const mapping::FrameResult& r) { return r.solve ? r.solve->time_s : 0.0; })
      .def_property_readonly("accepted", [](const mapping::FrameResult& r) { return r.solve ? r.solve->accepted : 0; })
      .def_property_readonly("rejected", [](const mapping::FrameResult& r) { return r.solve ? r.solve->rejected : 0; });
  py::class_<PyMapper>(m, "Mapper",
                       "The online mapper (docs/mapping.md): frames in one at a time, closures and a corrected map "
                       "out as they come.")
      .def(py::init([](std::shared_ptr<Vocabulary> vocabulary, bool odometric_inference, bool solve_online) {
             if (!vocabulary) throw std::invalid_argument("Mapper: a vocabulary is needed");
             PyMapper p;
             p.vocabulary = vocabulary;
             p.model = std::make_unique<FabMapModel>(vocabulary->tree(), FabMapOptions{});
             mapping::MapperOptions options;
             options.front_end.filter.inference.enabled = odometric_inference;
             options.solve_online = solve_online;
             p.mapper = std::make_unique<mapping::Mapper>(*p.model, options);
             return p;
           }),
           py::arg("vocabulary"), py::arg("odometric_inference") = true, py::arg("solve_online") = true)
      .def(
          "add_frame",
          [](PyMapper& p, double time_s, const Pose2& odometry,
             const py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>& image) {
            const cv::Mat view = ImageOf(image);
            py::gil_scoped_release release;
            const Observation z{p.vocabulary->Words(view), {}};
            return p.mapper->AddFrame({time_s, odometry}, z);
          },
          py::arg("time_s"), py::arg("odometry"), py::arg("image"),
          "The next frame: its time, the odometry pose then (any fixed origin) and the image.")
      .def("map", [](const PyMapper& p) { return PoseRows(p.mapper->Map()); },
           "Every frame's pose so far, rows [x, y, theta]: the last online solve's, later frames chained by odometry")
      .def_property_readonly("closures", [](const PyMapper& p) { return p.mapper->front_end().closures; })
      .def_property_readonly("graph", [](const PyMapper& p) { return PyPoseGraph{p.mapper->front_end().graph}; },
                             "the front end's pose graph so far")
      .def(
          "solve",
          [](const PyMapper& p) {
            py::gil_scoped_release release;
            return p.mapper->Solve().solved.optimization;
          },
          "The back end on everything so far as `catgraph map` solves it (the closure hierarchy, cascade).");
}

}  // namespace
}  // namespace catgraph

PYBIND11_MODULE(_catgraph, m) {
  m.doc() = "catgraph: robust pose graphs and CAT-Graph+ loop closures (docs/python.md)";
  static py::exception<catgraph::FileError> file_error(m, "FileError", PyExc_OSError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const catgraph::FileError& e) {
      file_error(e.what());
    }
  });
  using namespace catgraph;
  BindPoses(m);
  BindGraph(m);
  BindFactorGraph(m);
  BindOptimizer(m);
  BindEvaluation(m);
  BindSimulation(m);
  BindFrontEnd(m);
  BindMapping(m);
}

