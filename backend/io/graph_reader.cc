// The readers of graph_io.h. One pass tokenises and checks each line; a second
// pass assembles the graph and checks references between lines (edges to
// vertices, switch edges to switches, FIX to vertices), reporting the line of
// the reference.
#include <charconv>
#include <cmath>
#include <fstream>
#include <istream>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <system_error>
#include <vector>

#include <Eigen/Cholesky>

#include "backend/graph/name_table.h"
#include "backend/graph/pose_graph.h"
#include "backend/io/file_error.h"
#include "backend/io/graph_io.h"
#include "backend/io/internal/closure_metadata.h"
#include "backend/io/internal/text_line.h"

namespace catgraph {
namespace {

constexpr NameTable<GraphFormat, 4> kGraphFormatNames = {{
    {GraphFormat::kAuto, "auto"},
    {GraphFormat::kG2o, "g2o"},
    {GraphFormat::kToro, "toro"},
    {GraphFormat::kIsam, "isam"},
}};

enum class Family { kNone, kG2o, kToroOrIsam };

Family FamilyOfTag(std::string_view tag) {
  static const std::set<std::string_view> kG2oTags = {
      "VERTEX_SE2",          "EDGE_SE2",           "VERTEX_SE3:QUAT", "EDGE_SE3:QUAT",
      "FIX",                 "VERTEX_SWITCH",      "EDGE_SWITCH_PRIOR", "EDGE_SE2_SWITCHABLE",
      "EDGE_SE3_SWITCHABLE", "EDGE_SE2_MAXMIX"};
  // catgraph's comments before an edge exist only in g2o files.
  if (kG2oTags.contains(tag) || tag == kClosureMetadataTag || tag == kDecisionTag) return Family::kG2o;
  if (tag == "VERTEX2" || tag == "EDGE2" || tag == "EDGE3") return Family::kToroOrIsam;
  return Family::kNone;
}

int DimensionOfTag(std::string_view tag) {
  if (tag == "VERTEX_SE2" || tag == "EDGE_SE2" || tag == "EDGE_SE2_SWITCHABLE" ||
      tag == "EDGE_SE2_MAXMIX" || tag == "VERTEX2" || tag == "EDGE2") {
    return 2;
  }
  if (tag == "VERTEX_SE3:QUAT" || tag == "EDGE_SE3:QUAT" || tag == "EDGE_SE3_SWITCHABLE" ||
      tag == "EDGE3") {
    return 3;
  }
  return 0;  // dimension-free: FIX, switches
}

bool TagBelongsTo(std::string_view tag, GraphFormat format) {
  switch (format) {
    case GraphFormat::kG2o: return FamilyOfTag(tag) == Family::kG2o;
    case GraphFormat::kToro: return tag == "VERTEX2" || tag == "EDGE2";
    case GraphFormat::kIsam: return tag == "EDGE2" || tag == "EDGE3";
    case GraphFormat::kAuto: break;
  }
  return false;
}

std::string ExpectedTags(GraphFormat format) {
  switch (format) {
    case GraphFormat::kG2o:
      return "VERTEX_SE2, EDGE_SE2, VERTEX_SE3:QUAT, EDGE_SE3:QUAT, FIX, VERTEX_SWITCH, "
             "EDGE_SWITCH_PRIOR, EDGE_SE2_SWITCHABLE, EDGE_SE3_SWITCHABLE or EDGE_SE2_MAXMIX";
    case GraphFormat::kToro: return "VERTEX2 or EDGE2";
    case GraphFormat::kIsam: return "EDGE2 or EDGE3";
    case GraphFormat::kAuto: break;
  }
  return "a g2o, TORO or iSAM tag";
}

// Fills the symmetric matrix from its upper triangle, row by row (g2o order).
template <int N>
Eigen::Matrix<double, N, N> UpperTriangle(const Line& line, std::size_t first) {
  Eigen::Matrix<double, N, N> m;
  std::size_t k = first;
  for (int r = 0; r < N; ++r) {
    for (int c = r; c < N; ++c) {
      m(r, c) = m(c, r) = line.Number(k++, "information entry");
    }
  }
  return m;
}

// Real benchmark files hold information matrices whose translation and
// rotation blocks are positive definite while the coupling between them makes
// the whole matrix indefinite (se-sync/cubicle.g2o: 5021 of 16869 edges). SE-Sync reads
// only the blocks, so such files are accepted as written and counted by
// Summarize(); a matrix with an indefinite or singular block carries no usable
// information and is an error.
template <int N>
void CheckPositiveDefiniteBlocks(const Line& line, const Eigen::Matrix<double, N, N>& information) {
  constexpr int kTranslation = N == 3 ? 2 : 3;
  constexpr int kRotation = N - kTranslation;
  const Eigen::Matrix<double, kTranslation, kTranslation> t =
      information.template topLeftCorner<kTranslation, kTranslation>();
  const Eigen::Matrix<double, kRotation, kRotation> r =
      information.template bottomRightCorner<kRotation, kRotation>();
  if (t.llt().info() != Eigen::Success || r.llt().info() != Eigen::Success) {
    line.Fail(std::string(line.tag()) + ": the information matrix is not positive definite (its " +
              (t.llt().info() != Eigen::Success ? "translation" : "rotation") +
              " block is not); expected a symmetric positive-definite matrix");
  }
}

Eigen::Quaterniond Quaternion(const Line& line, std::size_t first) {
  // g2o order: qx qy qz qw.
  const Eigen::Quaterniond q(line.Number(first + 3, "qw"), line.Number(first, "qx"),
                             line.Number(first + 1, "qy"), line.Number(first + 2, "qz"));
  if (q.norm() < 1e-9) line.Fail(std::string(line.tag()) + ": expected a non-zero quaternion");
  // Components so large that the norm overflows would normalise to NaN.
  if (!std::isfinite(q.squaredNorm())) {
    line.Fail(std::string(line.tag()) + ": the quaternion's norm overflows; expected components of a unit quaternion");
  }
  return q;
}

Eigen::Quaterniond FromRollPitchYaw(double roll, double pitch, double yaw) {
  return Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
         Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
         Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX());
}

// Lines of the file, parsed but not yet cross-checked.
template <typename PoseT>
struct RawGraph {
  struct VertexLine {
    int line;
    Vertex<PoseT> vertex;
  };
  struct EdgeLine {
    int line;
    Constraint<PoseT> constraint;
    bool explicit_id = false;  // from a metadata comment; otherwise the edge's position
  };
  struct ReferenceLine {
    int line;
    std::int64_t id;
  };
  struct PriorLine {
    int line;
    std::int64_t id;
    SwitchPrior prior;
  };
  std::vector<VertexLine> vertices;
  std::vector<EdgeLine> edges;
  std::vector<VertexLine> switch_vertices;  // vertex.pose unused; value in switch_values
  std::vector<double> switch_values;
  std::vector<PriorLine> switch_priors;
  std::vector<ReferenceLine> fixes;
};

template <typename PoseT>
class GraphParser {
 public:
  GraphParser(const std::string& file, GraphFormat format, const ReadGraphOptions& options)
      : file_(file), format_(format), options_(options) {}

  void Parse(const Line& line, const std::optional<ClosureMetadata>& metadata);
  std::size_t edge_count() const { return raw_.edges.size(); }
  void SetLastEdgeDecision(const RobustDecision& decision) { raw_.edges.back().constraint.decision = decision; }
  // `self_edge_lines` receives the lines of the edges left out because they
  // join a vertex to itself.
  PoseGraph<PoseT> Assemble(int last_line, std::vector<int>& self_edge_lines) const;

 private:
  static constexpr int N = PoseT::kTangentDim;

  PoseT ParsePose(const Line& line, std::size_t first) const;
  void AddEdge(const Line& line, const std::optional<ClosureMetadata>& metadata,
               std::size_t first, std::optional<SwitchId> switch_id,
               std::optional<double> maxmix_weight);

  const std::string& file_;
  GraphFormat format_;
  const ReadGraphOptions& options_;
  RawGraph<PoseT> raw_;
};

template <>
Pose2 GraphParser<Pose2>::ParsePose(const Line& line, std::size_t first) const {
  return {line.Number(first, "x"), line.Number(first + 1, "y"), line.Number(first + 2, "theta")};
}

template <>
Pose3 GraphParser<Pose3>::ParsePose(const Line& line, std::size_t first) const {
  const Eigen::Vector3d t(line.Number(first, "x"), line.Number(first + 1, "y"),
                          line.Number(first + 2, "z"));
  if (format_ == GraphFormat::kIsam) {
    return {t, FromRollPitchYaw(line.Number(first + 3, "roll"), line.Number(first + 4, "pitch"),
                                line.Number(first + 5, "yaw"))};
  }
  return {t, Quaternion(line, first + 3)};
}

template <typename PoseT>
void GraphParser<PoseT>::AddEdge(const Line& line, const std::optional<ClosureMetadata>& metadata,
                                 std::size_t first, std::optional<SwitchId> switch_id,
                                 std::optional<double> maxmix_weight) {
  Constraint<PoseT> c;
  c.from = PoseId(line.Id(1, "the first vertex", options_.max_id));
  c.to = PoseId(line.Id(2, "the second vertex", options_.max_id));
  c.measurement.mean = ParsePose(line, first);
  const std::size_t info_first = first + (N == 3 ? 3 : (format_ == GraphFormat::kIsam ? 6 : 7));
  InformationMatrix<PoseT> information = InformationMatrix<PoseT>::Zero();
  if (format_ == GraphFormat::kToro) {
    // TORO: Ixx Ixy Iyy Itt Ixt Iyt.
    const double xx = line.Number(info_first, "Ixx"), xy = line.Number(info_first + 1, "Ixy");
    const double yy = line.Number(info_first + 2, "Iyy"), tt = line.Number(info_first + 3, "Itt");
    const double xt = line.Number(info_first + 4, "Ixt"), yt = line.Number(info_first + 5, "Iyt");
    information << xx, xy, xt, xy, yy, yt, xt, yt, tt;
  } else if (format_ == GraphFormat::kIsam) {
    // Square-root information R, upper triangle row by row: Omega = R^T R.
    Eigen::Matrix<double, N, N> r = UpperTriangle<N>(line, info_first);
    r.template triangularView<Eigen::StrictlyLower>().setZero();
    information = r.transpose() * r;
  } else {
    information = UpperTriangle<N>(line, info_first);
  }
  CheckPositiveDefiniteBlocks<N>(line, information);
  c.measurement.information = information;
  c.switch_id = switch_id;
  c.maxmix_weight = maxmix_weight;
  c.kind = c.IsBetweenConsecutivePoses() ? ClosureKind::kOdometry : ClosureKind::kUnknown;
  c.id = ClosureId(static_cast<std::int64_t>(raw_.edges.size()));
  if (metadata) {
    c.id = metadata->id;
    c.kind = metadata->kind;
    c.provenance = metadata->provenance;
  }
  raw_.edges.push_back({line.number(), std::move(c), metadata.has_value()});
}

template <typename PoseT>
void GraphParser<PoseT>::Parse(const Line& line, const std::optional<ClosureMetadata>& metadata) {
  const std::string_view tag = line.tag();
  const bool is_edge = tag.starts_with("EDGE") && tag != "EDGE_SWITCH_PRIOR";
  if (metadata && !is_edge) {
    line.Fail(std::string(kClosureMetadataTag) + " must be followed by an edge line, found " +
              std::string(tag));
  }
  if (!TagBelongsTo(tag, format_)) {
    line.Fail("unknown tag '" + std::string(tag) + "' for the " + std::string(ToString(format_)) +
              " format; expected " + ExpectedTags(format_));
  }
  constexpr bool k2d = N == 3;
  if (tag == "VERTEX_SE2" || tag == "VERTEX2" || tag == "VERTEX_SE3:QUAT") {
    line.ExpectValues(k2d ? 4 : 8, k2d ? "id x y theta" : "id x y z qx qy qz qw");
    Vertex<PoseT> v;
    v.id = PoseId(line.Id(1, "the vertex", options_.max_id));
    v.pose = ParsePose(line, 2);
    raw_.vertices.push_back({line.number(), v});
  } else if (tag == "EDGE_SE2" || tag == "EDGE_SE3:QUAT") {
    line.ExpectValues(k2d ? 11 : 30, k2d ? "i j dx dy dtheta and 6 information entries"
                                         : "i j x y z qx qy qz qw and 21 information entries");
    AddEdge(line, metadata, 3, std::nullopt, std::nullopt);
  } else if (tag == "EDGE2" && format_ == GraphFormat::kToro) {
    line.ExpectValues(11, "i j dx dy dtheta Ixx Ixy Iyy Itt Ixt Iyt");
    AddEdge(line, metadata, 3, std::nullopt, std::nullopt);
  } else if (tag == "EDGE2" || tag == "EDGE3") {  // iSAM
    line.ExpectValues(k2d ? 11 : 29,
                      k2d ? "i j dx dy dtheta and 6 square-root information entries"
                          : "i j x y z roll pitch yaw and 21 square-root information entries");
    AddEdge(line, metadata, 3, std::nullopt, std::nullopt);
  } else if (tag == "EDGE_SE2_SWITCHABLE" || tag == "EDGE_SE3_SWITCHABLE") {
    line.ExpectValues(k2d ? 12 : 31,
                      k2d ? "i j switch dx dy dtheta and 6 information entries"
                          : "i j switch x y z qx qy qz qw and 21 information entries");
    AddEdge(line, metadata, 4, SwitchId(line.Id(3, "the switch", options_.max_id)),
            std::nullopt);
  } else if (tag == "EDGE_SE2_MAXMIX") {
    line.ExpectValues(12, "i j weight dx dy dtheta and 6 information entries");
    const double weight = line.Number(3, "the weight");
    if (weight <= 0.0 || weight > 1.0) line.Fail("EDGE_SE2_MAXMIX: expected a weight in (0, 1]");
    AddEdge(line, metadata, 4, std::nullopt, weight);
  } else if (tag == "VERTEX_SWITCH") {
    line.ExpectValues(2, "id value");
    raw_.switch_vertices.push_back({line.number(), {PoseId(line.Id(1, "the switch", options_.max_id)), std::nullopt, false}});
    raw_.switch_values.push_back(line.Number(2, "the switch value"));
  } else if (tag == "EDGE_SWITCH_PRIOR") {
    line.ExpectValues(3, "switch prior-mean information");
    SwitchPrior prior{line.Number(2, "the prior mean"), line.Number(3, "the information")};
    if (prior.information <= 0.0) line.Fail("EDGE_SWITCH_PRIOR: expected a positive information");
    raw_.switch_priors.push_back({line.number(), line.Id(1, "the switch", options_.max_id), prior});
  } else if (tag == "FIX") {
    // g2o allows several ids on one FIX line.
    if (line.size() < 2) line.Fail("FIX: expected at least one vertex id");
    for (std::size_t k = 1; k < line.size(); ++k) {
      raw_.fixes.push_back({line.number(), line.Id(k, "the vertex", options_.max_id)});
    }
  } else {
    line.Fail("unknown tag '" + std::string(tag) + "'; expected " + ExpectedTags(format_));
  }
}


template <typename PoseT>
PoseGraph<PoseT> GraphParser<PoseT>::Assemble(int last_line, std::vector<int>& self_edge_lines) const {
  PoseGraph<PoseT> graph;
  // g2o keeps poses and switches in one id space.
  std::map<std::int64_t, int> defined_at;
  auto define = [&](std::int64_t id, int line, const char* what) {
    auto [it, inserted] = defined_at.emplace(id, line);
    if (!inserted) {
      throw FileError(file_, line,
                      std::string("duplicate vertex id ") + std::to_string(id) + " (" + what +
                          "); it was first defined on line " + std::to_string(it->second));
    }
  };
  for (const auto& [line, vertex] : raw_.vertices) {
    define(vertex.id.value(), line, "pose");
    graph.vertices.emplace(vertex.id, vertex);
  }
  for (std::size_t k = 0; k < raw_.switch_vertices.size(); ++k) {
    const auto& [line, vertex] = raw_.switch_vertices[k];
    define(vertex.id.value(), line, "switch");
    const SwitchId id(vertex.id.value());
    graph.switches.emplace(id, SwitchVariable{id, raw_.switch_values[k], std::nullopt});
  }
  for (const auto& [line, id, prior] : raw_.switch_priors) {
    auto it = graph.switches.find(SwitchId(id));
    if (it == graph.switches.end()) {
      throw FileError(file_, line, "EDGE_SWITCH_PRIOR: switch " + std::to_string(id) +
                                       " is not defined; expected a VERTEX_SWITCH line for it");
    }
    it->second.prior = prior;
  }
  const bool edges_only = raw_.vertices.empty();
  // An edge without a metadata comment is known by its position among the
  // edges, unless a commented edge holds that id (an edge appended to a file
  // catgraph wrote, which numbers closures sparsely): then by the next id
  // above every id in the file.
  std::set<ClosureId> explicit_ids;
  for (const auto& e : raw_.edges) {
    if (e.explicit_id) explicit_ids.insert(e.constraint.id);
  }
  std::int64_t next_free = explicit_ids.empty() ? 0 : explicit_ids.rbegin()->value() + 1;
  next_free = std::max(next_free, static_cast<std::int64_t>(raw_.edges.size()));
  std::set<ClosureId> closure_ids;
  for (const auto& [line, read, explicit_id] : raw_.edges) {
    Constraint<PoseT> constraint = read;
    if (!explicit_id && explicit_ids.contains(constraint.id)) constraint.id = ClosureId(next_free++);
    if (constraint.from == constraint.to && (edges_only || graph.vertices.contains(constraint.from))) {
      self_edge_lines.push_back(line);
      continue;
    }
    for (const PoseId end : {constraint.from, constraint.to}) {
      if (graph.vertices.contains(end)) continue;
      if (!edges_only) {
        throw FileError(file_, line, "edge refers to vertex " + std::to_string(end.value()) +
                                         ", which is not defined; expected a vertex line for it");
      }
      if (graph.switches.contains(SwitchId(end.value()))) {
        throw FileError(file_, line, "edge refers to switch " + std::to_string(end.value()) +
                                         " as a pose");
      }
      graph.vertices.emplace(end, Vertex<PoseT>{end, std::nullopt, false});
    }
    if (constraint.switch_id && !graph.switches.contains(*constraint.switch_id)) {
      throw FileError(file_, line, "switchable edge refers to switch " +
                                       std::to_string(constraint.switch_id->value()) +
                                       ", which is not defined; expected a VERTEX_SWITCH line");
    }
    if (!closure_ids.insert(constraint.id).second) {
      throw FileError(file_, line, "duplicate closure id " + std::to_string(constraint.id.value()));
    }
    graph.constraints.push_back(std::move(constraint));
  }
  for (const auto& [line, id] : raw_.fixes) {
    auto it = graph.vertices.find(PoseId(id));
    if (it == graph.vertices.end()) {
      throw FileError(file_, line, "FIX refers to vertex " + std::to_string(id) +
                                       ", which is not defined");
    }
    it->second.fixed = true;
  }
  if (graph.vertices.empty()) {
    throw FileError(file_, std::max(last_line, 1),
                    "no vertex or edge in the file; expected a pose graph in " +
                        std::string(ToString(format_)) + " format");
  }
  return graph;
}

struct PendingLine {
  int number;
  std::string text;
};

// Decides the format from the first tag when it was not given.
GraphFormat DetectFormat(const std::string& name, const std::vector<PendingLine>& lines,
                         GraphFormat requested) {
  if (requested != GraphFormat::kAuto) return requested;
  bool any_vertex2 = false;
  for (const PendingLine& line : lines) {
    const auto tokens = Tokenize(line.text);
    if (tokens.front() == "VERTEX2") any_vertex2 = true;
  }
  for (const PendingLine& line : lines) {
    const auto tokens = Tokenize(line.text);
    switch (FamilyOfTag(tokens.front())) {
      case Family::kG2o: return GraphFormat::kG2o;
      case Family::kToroOrIsam:
        if (any_vertex2 || name.ends_with(".graph")) return GraphFormat::kToro;
        return GraphFormat::kIsam;
      case Family::kNone:
        throw FileError(name, line.number,
                        "unknown tag '" + std::string(tokens.front()) +
                            "'; expected a g2o, TORO or iSAM tag such as VERTEX_SE2, "
                            "EDGE_SE3:QUAT, VERTEX2 or EDGE2");
    }
  }
  return GraphFormat::kG2o;
}

template <typename PoseT>
PoseGraph<PoseT> ParseLines(const std::string& name, const std::vector<PendingLine>& lines,
                            GraphFormat format, const ReadGraphOptions& options, int last_line,
                            std::vector<int>& self_edge_lines) {
  GraphParser<PoseT> parser(name, format, options);
  std::optional<ClosureMetadata> metadata;
  std::optional<RobustDecision> decision;
  for (const PendingLine& pending : lines) {
    if (pending.text.starts_with(kDecisionTag)) {
      if (decision) {
        throw FileError(name, pending.number, std::string(kDecisionTag) + " twice in a row; expected an edge line");
      }
      std::string error;
      decision = ParseDecision(pending.text, &error);
      if (!decision) throw FileError(name, pending.number, error);
      continue;
    }
    if (pending.text.starts_with(kClosureMetadataTag)) {
      if (metadata) {
        throw FileError(name, pending.number, std::string(kClosureMetadataTag) +
                                                  " twice in a row; expected an edge line");
      }
      std::string error;
      metadata = ParseClosureMetadata(pending.text, &error);
      if (!metadata) throw FileError(name, pending.number, error);
      continue;
    }
    Line line(name, pending.number, Tokenize(pending.text));
    const std::size_t edges = parser.edge_count();
    parser.Parse(line, metadata);
    metadata.reset();
    if (decision) {
      if (parser.edge_count() == edges) line.Fail(std::string(kDecisionTag) + " must be followed by an edge line");
      parser.SetLastEdgeDecision(*decision);
      decision.reset();
    }
  }
  if (metadata || decision) {
    throw FileError(name, last_line, std::string(metadata ? kClosureMetadataTag : kDecisionTag) +
                                         " at the end of the file; expected an edge line after it");
  }
  return parser.Assemble(last_line, self_edge_lines);
}

}  // namespace

std::string_view ToString(GraphFormat format) { return NameOf(kGraphFormatNames, format); }

std::optional<GraphFormat> GraphFormatFromString(std::string_view text) {
  return ValueOf(kGraphFormatNames, text);
}

GraphFile ReadGraph(std::istream& in, const std::string& name, const ReadGraphOptions& options) {
  std::vector<PendingLine> lines;
  std::string text;
  int number = 0;
  int dimension = 0;
  int dimension_line = 0;
  while (ReadBoundedLine(in, text, options.max_line_bytes, name, number,
                         "one vertex or edge per line")) {
    ++number;
    const auto tokens = Tokenize(text);
    if (tokens.empty()) continue;
    if (tokens.front().starts_with("#")) {
      if (text.starts_with(kClosureMetadataTag) || text.starts_with(kDecisionTag)) lines.push_back({number, text});
      continue;
    }
    const int tag_dimension = DimensionOfTag(tokens.front());
    if (tag_dimension != 0) {
      if (dimension == 0) {
        dimension = tag_dimension;
        dimension_line = number;
      } else if (dimension != tag_dimension) {
        throw FileError(name, number,
                        std::string(tokens.front()) + " is a " + std::to_string(tag_dimension) +
                            "D tag but line " + std::to_string(dimension_line) + " was " +
                            std::to_string(dimension) + "D; expected one dimension per file");
      }
    }
    lines.push_back({number, text});
  }
  if (in.bad()) throw FileError(name, number, "read error");
  if (lines.empty()) {
    throw FileError(name, std::max(number, 1),
                    number == 0 ? "the file is empty; expected a pose graph"
                                : "no vertex or edge in the file; expected a pose graph");
  }
  GraphFile result;
  result.format = DetectFormat(name, lines, options.format);
  if (dimension == 3) {
    result.graph = ParseLines<Pose3>(name, lines, result.format, options, number, result.self_edge_lines);
  } else {
    result.graph = ParseLines<Pose2>(name, lines, result.format, options, number, result.self_edge_lines);
  }
  return result;
}

GraphFile ReadGraphFile(const std::filesystem::path& path, const ReadGraphOptions& options) {
  std::ifstream in = OpenForReading(path, "a pose-graph file (g2o, TORO or iSAM)");
  return ReadGraph(in, path.string(), options);
}

}  // namespace catgraph
