#include "backend/io/closure_labels.h"

#include <charconv>
#include <istream>
#include <map>
#include <ostream>

#include "backend/io/atomic_file.h"
#include "backend/io/internal/text_line.h"

namespace catgraph {

std::vector<ClosureLabel> ReadClosureLabels(std::istream& in, const std::string& name, std::vector<int>* lines) {
  std::vector<ClosureLabel> labels;
  std::map<ClosureId, int> line_of;  // for repeated ids
  std::string text;
  int number = 0;
  constexpr std::int64_t kMaxId = std::int64_t{1} << 40;
  while (ReadBoundedLine(in, text, 4096, name, number, "one closure per line")) {
    ++number;
    if (!text.empty() && text.back() == '\r') text.pop_back();
    if (number == 1) {
      if (text != kClosureLabelsHeader) {
        throw FileError(name, 1, "expected the header '" + std::string(kClosureLabelsHeader) +
                                     "' (a labels file written by catgraph inject)");
      }
      continue;
    }
    if (text.empty()) continue;
    const Line line(name, number, SplitCsv(text), "closure label");
    if (line.size() != 7) {
      line.Fail("found " + std::to_string(line.size()) + " fields; expected 7 (" +
                kClosureLabelsHeader + ")");
    }
    ClosureLabel label;
    label.id = ClosureId(line.Id(0, "closure_id", kMaxId));
    label.from = PoseId(line.Id(1, "from", kMaxId));
    label.to = PoseId(line.Id(2, "to", kMaxId));
    const std::int64_t outlier = line.Id(3, "outlier", 1);
    label.outlier = outlier == 1;
    const auto kind = ClosureKindFromString(line.token(4));
    if (!kind) {
      line.Fail("unknown closure kind '" + std::string(line.token(4)) +
                "'; expected odometry, visual, inferred, injected or unknown");
    }
    label.kind = *kind;
    if (!line.token(5).empty()) label.group = static_cast<int>(line.Id(5, "group", 1 << 30));
    if (!line.token(6).empty()) label.parent = ClosureId(line.Id(6, "parent", kMaxId));
    if (const auto [at, fresh] = line_of.emplace(label.id, number); !fresh) {
      line.Fail("closure_id " + std::to_string(label.id.value()) + " is labelled again (first on line " +
                std::to_string(at->second) + "); expected one row per closure");
    }
    labels.push_back(label);
    if (lines) lines->push_back(number);
  }
  if (in.bad()) throw FileError(name, number, "read error");
  if (number == 0) throw FileError(name, 0, "the file is empty; expected closure labels");
  if (labels.empty()) throw FileError(name, 0, "holds the header alone; expected a row per loop closure");
  return labels;
}

std::vector<ClosureLabel> ReadClosureLabelsFile(const std::filesystem::path& path, std::vector<int>* lines) {
  std::ifstream in = OpenForReading(path, "a closure-labels CSV file");
  return ReadClosureLabels(in, path.string(), lines);
}

void WriteClosureLabels(const std::vector<ClosureLabel>& labels, std::ostream& out) {
  out << kClosureLabelsHeader << '\n';
  for (const ClosureLabel& l : labels) {
    out << l.id.value() << ',' << l.from.value() << ',' << l.to.value() << ','
        << (l.outlier ? 1 : 0) << ',' << ToString(l.kind) << ',';
    if (l.group) out << *l.group;
    out << ',';
    if (l.parent) out << l.parent->value();
    out << '\n';
  }
}

void WriteClosureLabelsFile(const std::vector<ClosureLabel>& labels,
                            const std::filesystem::path& path) {
  WriteFileAtomically(path, [&](std::ostream& out) { WriteClosureLabels(labels, out); });
}

}  // namespace catgraph
