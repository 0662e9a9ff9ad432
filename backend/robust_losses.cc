#include "backend/robust_losses.h"

namespace catgraph {

void DcsLoss::Evaluate(double x, double rho[3]) const {
  if (x <= phi_) {
    rho[0] = x;
    rho[1] = 1.0;
    rho[2] = 0.0;
    return;
  }
  const double d = phi_ + x;
  rho[0] = 3.0 * phi_ - 4.0 * phi_ * phi_ / d;
  rho[1] = 4.0 * phi_ * phi_ / (d * d);
  rho[2] = -8.0 * phi_ * phi_ / (d * d * d);
}

double DcsLoss::SquaredWeight(double phi, double chi2) {
  const double w = chi2 <= phi ? 1.0 : 2.0 * phi / (phi + chi2);
  return w * w;
}

}  // namespace catgraph
