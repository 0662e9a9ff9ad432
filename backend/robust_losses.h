// Robust losses beyond Ceres' own.
#ifndef CATGRAPH_BACKEND_ROBUST_LOSSES_H_
#define CATGRAPH_BACKEND_ROBUST_LOSSES_H_

#include <ceres/loss_function.h>

namespace catgraph {

// Dynamic covariance scaling (Agarwal et al., ICRA 2013) as an M-estimator.
// DCS scales an edge with chi2 = e^T Omega e by w = min(1, 2 Phi / (Phi + chi2))
// so that it contributes w^2 chi2 to the linear system. An M-estimator whose
// IRLS weight rho'(x) is that w^2 is, with x = chi2:
//   rho(x) = x                         for x <= Phi
//   rho(x) = 3 Phi - 4 Phi^2 / (Phi + x)   for x > Phi
// continuous with its derivative at Phi, bounded by 3 Phi, rho' > 0 everywhere
// (unlike g2o's IRLS kernel, whose rho' can turn negative).
class DcsLoss : public ceres::LossFunction {
 public:
  explicit DcsLoss(double phi) : phi_(phi) {}
  void Evaluate(double x, double rho[3]) const override;
  // w^2 = rho'(x): the weight DCS gives an edge of this chi2.
  static double SquaredWeight(double phi, double chi2);

 private:
  double phi_;
};

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_ROBUST_LOSSES_H_
