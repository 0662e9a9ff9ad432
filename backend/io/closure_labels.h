// Closure labels: which loop closures of a graph are outliers. Written by
// `catgraph inject`, read by `catgraph evaluate` to score the closures a
// robust back end accepted.
//
// CSV with a header line, one row per loop closure of the spoiled graph (true
// and false, in graph order):
//   closure_id,from,to,outlier,kind,group,parent
// outlier is 1 for an injected edge, 0 otherwise; kind as in closure.h;
// group the 0-based injection group (empty for true closures); parent the
// closure id of a hierarchical child's false visual closure (else empty).
#ifndef CATGRAPH_BACKEND_IO_CLOSURE_LABELS_H_
#define CATGRAPH_BACKEND_IO_CLOSURE_LABELS_H_

#include <filesystem>
#include <iosfwd>
#include <string>
#include <vector>

#include "backend/graph/closure_label.h"

namespace catgraph {


inline constexpr char kClosureLabelsHeader[] = "closure_id,from,to,outlier,kind,group,parent";

// A file with no label (the header alone) and a closure id given twice are
// errors. `lines`, when given, receives each label's line number.
std::vector<ClosureLabel> ReadClosureLabels(std::istream& in, const std::string& name,
                                            std::vector<int>* lines = nullptr);
std::vector<ClosureLabel> ReadClosureLabelsFile(const std::filesystem::path& path, std::vector<int>* lines = nullptr);
void WriteClosureLabels(const std::vector<ClosureLabel>& labels, std::ostream& out);
void WriteClosureLabelsFile(const std::vector<ClosureLabel>& labels,
                            const std::filesystem::path& path);

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_IO_CLOSURE_LABELS_H_
