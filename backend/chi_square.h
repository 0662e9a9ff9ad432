// The chi-square distribution, for gates on squared Mahalanobis distances.
#ifndef CATGRAPH_BACKEND_CHI_SQUARE_H_
#define CATGRAPH_BACKEND_CHI_SQUARE_H_

namespace catgraph {

// P(X <= x) for X ~ chi2(dof); dof >= 1, x >= 0.
double ChiSquareCdf(int dof, double x);
// The x with ChiSquareCdf(dof, x) = probability; 0 < probability < 1.
// Throws std::invalid_argument outside those ranges.
double ChiSquareQuantile(int dof, double probability);

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_CHI_SQUARE_H_
