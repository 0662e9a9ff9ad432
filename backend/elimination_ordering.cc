#include "backend/elimination_ordering.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>

#include <cholmod.h>

namespace catgraph {
namespace {

// Nested dissection is tried when minimum degree's factorisation of the
// variables left after the fill-free ones takes at least this many
// operations counted per block (a 2D pose's block is 3 x 3: about 27 times
// as many on the scalars). Below it the factorisation takes about a
// millisecond, and the dissection would cost as much as it saves.
constexpr double kDissectionMinFlops = 1e6;

// CHOLMOD's workspace, silent: a failure is reported by a null result.
class Cholmod {
 public:
  Cholmod() {
    cholmod_start(&common_);
    common_.print = 0;
  }
  ~Cholmod() { cholmod_finish(&common_); }
  Cholmod(const Cholmod&) = delete;
  Cholmod& operator=(const Cholmod&) = delete;
  cholmod_common* get() { return &common_; }

 private:
  cholmod_common common_;
};

// A graph's variables (the keys its factors read, not held constant),
// numbered in the order the factors first read them; each variable's first
// coordinate in the tangent space; the variables each factor reads.
struct Structure {
  std::vector<Key> keys;
  std::vector<int> offsets;  // keys.size() + 1 entries
  std::vector<std::vector<int>> factors;
  // Every key the factors read: its variable's number, or kConstant.
  static constexpr int kConstant = -1;
  struct KeyHash {
    std::size_t operator()(const Key& key) const {
      return std::hash<std::int64_t>()(key.id) * 2 + static_cast<std::size_t>(key.type);
    }
  };
  std::unordered_map<Key, int, KeyHash> index;
};

Structure StructureOf(const FactorGraph& graph, const Values& values) {
  Structure s;
  s.offsets.push_back(0);
  s.factors.reserve(graph.size());
  s.index.reserve(values.size());
  // Each key's value, kind and constancy are looked up once, when a factor
  // first reads it.
  for (const auto& factor : graph.factors()) {
    std::vector<int> variables;
    for (const Key key : factor->keys()) {
      auto it = s.index.find(key);
      if (it == s.index.end()) {
        if (!values.Contains(key)) {
          throw std::invalid_argument("FillReducingOrder: a factor uses " + ToString(key) +
                                      ", which has no value");
        }
        int number = Structure::kConstant;
        if (!graph.constant_keys().contains(key)) {
          number = static_cast<int>(s.keys.size());
          s.keys.push_back(key);
          s.offsets.push_back(s.offsets.back() + Values::TangentSize(values.KindOf(key)));
        }
        it = s.index.emplace(key, number).first;
      }
      if (it->second != Structure::kConstant) variables.push_back(it->second);
    }
    s.factors.push_back(std::move(variables));
  }
  return s;
}

// The lower triangle (and diagonal) of a symmetric pattern from the cliques
// `groups` of its rows, n rows in all; null on failure.
cholmod_sparse* LowerPattern(int n, const std::vector<std::vector<int>>& groups, cholmod_common* cc) {
  std::size_t entries = static_cast<std::size_t>(n);
  for (const auto& g : groups) entries += g.size() * (g.size() - 1) / 2;
  cholmod_triplet* t = cholmod_allocate_triplet(n, n, entries, -1, CHOLMOD_PATTERN, cc);
  if (!t) return nullptr;
  int* rows = static_cast<int*>(t->i);
  int* cols = static_cast<int*>(t->j);
  std::size_t k = 0;
  auto add = [&](int row, int col) {
    rows[k] = std::max(row, col);
    cols[k] = std::min(row, col);
    ++k;
  };
  for (int i = 0; i < n; ++i) add(i, i);
  for (const auto& g : groups) {
    for (std::size_t a = 0; a < g.size(); ++a) {
      for (std::size_t b = 0; b < a; ++b) add(g[a], g[b]);
    }
  }
  t->nnz = k;
  cholmod_sparse* pattern = cholmod_triplet_to_sparse(t, k, cc);
  cholmod_free_triplet(&t, cc);
  return pattern;
}

// J^T J's pattern, a row per scalar.
cholmod_sparse* ScalarPattern(const Structure& s, cholmod_common* cc) {
  std::vector<std::vector<int>> groups;
  groups.reserve(s.factors.size());
  for (const auto& r : s.factors) {
    std::vector<int> scalars;
    for (const int b : r) {
      for (int i = s.offsets[b]; i < s.offsets[b + 1]; ++i) scalars.push_back(i);
    }
    groups.push_back(std::move(scalars));
  }
  return LowerPattern(s.offsets.back(), groups, cc);
}

// J^T J's pattern, a row per variable `row` numbers (row[v] >= 0), the
// others left out; `rows` of them.
cholmod_sparse* BlockPattern(const Structure& s, const std::vector<int>& row, int rows, cholmod_common* cc) {
  std::vector<std::vector<int>> groups;
  groups.reserve(s.factors.size());
  for (const auto& r : s.factors) {
    std::vector<int> kept;
    for (const int b : r) {
      if (row[b] >= 0) kept.push_back(row[b]);
    }
    if (kept.size() > 1) groups.push_back(std::move(kept));
  }
  return LowerPattern(rows, groups, cc);
}

// The variables whose elimination makes no fill: those one factor reads
// together with every variable any factor reads with them (a switch and
// the two poses of its constraint). Their neighbours are a clique already,
// and stay one as other such variables go.
std::vector<char> FillFreeVariables(const Structure& s) {
  std::vector<std::vector<int>> reading(s.keys.size());
  for (std::size_t r = 0; r < s.factors.size(); ++r) {
    for (const int b : s.factors[r]) reading[b].push_back(static_cast<int>(r));
  }
  std::vector<char> fill_free(s.keys.size(), 0);
  std::vector<int> neighbours;
  for (std::size_t b = 0; b < s.keys.size(); ++b) {
    neighbours.clear();
    std::size_t widest = 0;
    for (const int r : reading[b]) {
      neighbours.insert(neighbours.end(), s.factors[r].begin(), s.factors[r].end());
      widest = std::max(widest, s.factors[r].size());
    }
    std::sort(neighbours.begin(), neighbours.end());
    neighbours.erase(std::unique(neighbours.begin(), neighbours.end()), neighbours.end());
    // The widest factor reads b and widest - 1 others, all among the
    // neighbours: it reads every neighbour when there are no more.
    fill_free[b] = neighbours.size() <= std::max<std::size_t>(widest, 1);
  }
  return fill_free;
}

// CHOLMOD's elimination order of `pattern` by `method` (CHOLMOD_AMD, ...)
// and the operations of the factorisation in that order; empty on failure.
std::pair<std::vector<int>, double> Analyzed(cholmod_sparse* pattern, int method, cholmod_common* cc) {
  cc->nmethods = 1;
  cc->method[0].ordering = method;
  cc->postorder = 1;
  cc->supernodal = CHOLMOD_SIMPLICIAL;
  cholmod_factor* factor = cholmod_analyze(pattern, cc);
  if (!factor) return {};
  const int* perm = static_cast<const int*>(factor->Perm);
  std::vector<int> order(perm, perm + factor->n);
  cholmod_free_factor(&factor, cc);
  return {std::move(order), cc->method[0].fl};
}

std::vector<Key> KeysOf(const Structure& s, const std::vector<int>& variables) {
  std::vector<Key> keys;
  keys.reserve(variables.size());
  for (const int v : variables) keys.push_back(s.keys[v]);
  return keys;
}

}  // namespace

std::vector<Key> FillReducingOrder(const FactorGraph& graph, const Values& values) {
  const Structure s = StructureOf(graph, values);
  // The fill-free variables first; the others ordered on their own
  // pattern, a row per variable.
  const std::vector<char> fill_free = FillFreeVariables(s);
  std::vector<int> order;
  std::vector<int> rest;
  std::vector<int> row(s.keys.size(), -1);
  for (std::size_t b = 0; b < s.keys.size(); ++b) {
    if (fill_free[b]) {
      order.push_back(static_cast<int>(b));
    } else {
      row[b] = static_cast<int>(rest.size());
      rest.push_back(static_cast<int>(b));
    }
  }
  // A dense factorisation bounds the operations from above: on so few
  // variables there is nothing to gain.
  if (std::pow(static_cast<double>(rest.size()), 3) / 3.0 < kDissectionMinFlops) return {};
  Cholmod cc;
  cholmod_sparse* pattern = BlockPattern(s, row, static_cast<int>(rest.size()), cc.get());
  if (!pattern) return {};
  const double minimum_degree_flops = Analyzed(pattern, CHOLMOD_AMD, cc.get()).second;
  std::vector<int> dissection;
  if (minimum_degree_flops >= kDissectionMinFlops) {
    auto [nd, nd_flops] = Analyzed(pattern, CHOLMOD_NESDIS, cc.get());
    if (nd.size() == rest.size() && nd_flops < minimum_degree_flops) dissection = std::move(nd);
  }
  cholmod_free_sparse(&pattern, cc.get());
  if (dissection.empty()) return {};
  for (const int r : dissection) order.push_back(rest[r]);
  return KeysOf(s, order);
}

std::vector<Key> MinimumDegreeOrder(const FactorGraph& graph, const Values& values) {
  const Structure s = StructureOf(graph, values);
  if (s.keys.empty()) return {};
  std::vector<int> row(s.keys.size());
  for (std::size_t b = 0; b < row.size(); ++b) row[b] = static_cast<int>(b);
  Cholmod cc;
  cholmod_sparse* pattern = BlockPattern(s, row, static_cast<int>(row.size()), cc.get());
  if (!pattern) return {};
  const std::vector<int> order = Analyzed(pattern, CHOLMOD_AMD, cc.get()).first;
  cholmod_free_sparse(&pattern, cc.get());
  return KeysOf(s, order);
}

FactorFill FillOf(const FactorGraph& graph, const Values& values, const std::vector<Key>& order) {
  const Structure s = StructureOf(graph, values);
  std::vector<int> scalars;
  std::vector<char> seen(s.keys.size(), 0);
  for (const Key key : order) {
    const auto it = s.index.find(key);
    if (it == s.index.end() || it->second == Structure::kConstant || seen[it->second]) return {};
    seen[it->second] = 1;
    for (int i = s.offsets[it->second]; i < s.offsets[it->second + 1]; ++i) scalars.push_back(i);
  }
  if (scalars.empty() || scalars.size() != static_cast<std::size_t>(s.offsets.back())) return {};
  Cholmod cc;
  cholmod_sparse* pattern = ScalarPattern(s, cc.get());
  if (!pattern) return {};
  cc.get()->nmethods = 1;
  cc.get()->method[0].ordering = CHOLMOD_GIVEN;
  cc.get()->postorder = 0;
  cc.get()->supernodal = CHOLMOD_SIMPLICIAL;
  cholmod_factor* factor = cholmod_analyze_p(pattern, scalars.data(), nullptr, 0, cc.get());
  cholmod_free_sparse(&pattern, cc.get());
  if (!factor) return {};
  cholmod_free_factor(&factor, cc.get());
  return {cc.get()->method[0].lnz, cc.get()->method[0].fl};
}

}  // namespace catgraph
