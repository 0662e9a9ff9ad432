// The chi-square distribution, for gates on squared Mahalanobis distances.
#ifndef CATGRAPH_BACKEND_CHI_SQUARE_H_
#define CATGRAPH_BACKEND_CHI_SQUARE_H_

namespace catgraph {

// P(X <= x) for X ~ chi2(dof); dof >= 1, x >= 0.
double ChiSquareCdf(int dof, double x);
// The x with ChiSquareCdf(dof, x) = probability; 0 < probability < 1.
// Throws std::invalid_argument outside those ranges.
double ChiSquareQuantile(int dof, double probability);

// P(A + c B <= x) for independent A ~ chi2(dof_a), B ~ chi2(dof_b); c > 0.
double ChiSquareSumCdf(int dof_a, int dof_b, double c, double x);

// The distribution of SE-Sync's chordal cost of one relative-pose
// measurement, kappa |R_j - R_i R_z|_F^2 + tau |t_j - t_i - R_i t_z|^2 with
// ChordalWeightsOf's kappa and tau, at the true poses, when the measurement's
// noise is the Gaussian of its g2o information, isotropic in translation and
// (3D) in rotation; small angles. tau |.|^2 is the translation's chi2; as
// |R - I|_F^2 = 2 theta^2 to second order, the rotation term is
//   2D: 2 chi2(1): kappa = I_theta_theta, twice the angle's chi2;
//   3D: 4 chi2(3): kappa = 3 / (2 trace(Sigma)) with Sigma the covariance of
//       g2o's rotation error, the quaternion's vector part, about theta / 2.
// So chi2(2) + 2 chi2(1) in 2D and chi2(3) + 4 chi2(3) in 3D. P(X <= x) for
// dimension 2 or 3.
double ChordalCostCdf(int dimension, double x);
// The x with ChordalCostCdf(dimension, x) = probability; 0 < probability < 1.
double ChordalCostQuantile(int dimension, double probability);

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_CHI_SQUARE_H_
