#include "backend/chi_square.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace catgraph {
namespace {

// Regularised lower incomplete gamma P(a, x): the power series for
// x < a + 1, the continued fraction (modified Lentz) otherwise.
double RegularizedLowerGamma(double a, double x) {
  if (x <= 0.0) return 0.0;
  const double log_prefix = a * std::log(x) - x - std::lgamma(a);
  if (x < a + 1.0) {
    double term = 1.0 / a, sum = term;
    for (int n = 1; n < 1000 && std::abs(term) > 1e-17 * std::abs(sum); ++n) {
      term *= x / (a + n);
      sum += term;
    }
    return sum * std::exp(log_prefix);
  }
  constexpr double kTiny = 1e-300;
  double b = x + 1.0 - a, c = 1.0 / kTiny, d = 1.0 / b, h = d;
  for (int i = 1; i < 1000; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < 1e-16) break;
  }
  return 1.0 - std::exp(log_prefix) * h;
}

}  // namespace

double ChiSquareCdf(int dof, double x) {
  if (dof < 1) throw std::invalid_argument("ChiSquareCdf: dof must be >= 1");
  return RegularizedLowerGamma(0.5 * dof, 0.5 * x);
}

double ChiSquareQuantile(int dof, double probability) {
  if (dof < 1 || !(probability > 0.0 && probability < 1.0)) {
    throw std::invalid_argument("ChiSquareQuantile: need dof >= 1 and 0 < p < 1, got dof " +
                                std::to_string(dof) + ", p " + std::to_string(probability));
  }
  double lo = 0.0, hi = dof + 10.0;
  while (ChiSquareCdf(dof, hi) < probability) hi *= 2.0;
  for (int i = 0; i < 200 && hi - lo > 1e-12 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (ChiSquareCdf(dof, mid) < probability ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace catgraph
