// The order in which the sparse Cholesky factorisation eliminates a factor
// graph's variables.
//
// Ceres orders the normal equations J^T J of SPARSE_NORMAL_CHOLESKY by
// approximate minimum degree on the parameter blocks. On a pose graph whose
// loop closures join distant poses (false closures above all) a nested
// dissection (METIS, through CHOLMOD) leaves a sparser factor: fewer of the
// floating-point operations that dominate each iteration of a large solve.
// On short or clean graphs minimum degree may do as well or better.
//
// FillReducingOrder first eliminates the variables whose elimination makes
// no fill (a switch: one factor reads it with every variable any factor
// reads it with), then orders the others by nested dissection on their
// block pattern, where CHOLMOD's symbolic analysis counts fewer operations
// for it than for minimum degree (counted per block: the poses of a pose
// graph are all one size). Optimize() hands it to Ceres, a group per
// variable.
#ifndef CATGRAPH_BACKEND_ELIMINATION_ORDERING_H_
#define CATGRAPH_BACKEND_ELIMINATION_ORDERING_H_

#include <vector>

#include "backend/factor_graph.h"

namespace catgraph {

// The variables of `graph` (the keys its factors read that are not held
// constant) in elimination order; empty where Ceres' own order is kept:
// when minimum degree's factorisation takes under a million operations
// counted per block (about a millisecond: the dissection would cost what it
// saves; docs/backend.md), when nested dissection does not count fewer, or
// when CHOLMOD fails. Every key a factor reads must be in `values`; throws
// std::invalid_argument otherwise. Deterministic: it depends on the
// factors and their order only.
std::vector<Key> FillReducingOrder(const FactorGraph& graph, const Values& values);

// Approximate minimum degree on the variables, as Ceres orders them by
// default: for comparisons.
std::vector<Key> MinimumDegreeOrder(const FactorGraph& graph, const Values& values);

// The fill of eliminating the variables in `order` (each variable's
// coordinates in its tangent space together): the factor's nonzeros and the
// floating-point operations of the numeric factorisation, as CHOLMOD's
// symbolic analysis counts them. Zero when `order` does not list every
// variable exactly once.
struct FactorFill {
  double nonzeros = 0.0;
  double flops = 0.0;
};
FactorFill FillOf(const FactorGraph& graph, const Values& values, const std::vector<Key>& order);

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_ELIMINATION_ORDERING_H_
