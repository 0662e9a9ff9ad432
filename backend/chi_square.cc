#include "backend/chi_square.h"

#include <algorithm>
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

// The x in [0, inf) with cdf(x) = probability, cdf increasing, by bisection.
template <typename Cdf>
double Quantile(const Cdf& cdf, double start, double probability) {
  double lo = 0.0, hi = start;
  while (cdf(hi) < probability) hi *= 2.0;
  for (int i = 0; i < 200 && hi - lo > 1e-12 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (cdf(mid) < probability ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
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
  return Quantile([dof](double x) { return ChiSquareCdf(dof, x); }, dof + 10.0, probability);
}

double ChiSquareSumCdf(int dof_a, int dof_b, double c, double x) {
  if (dof_a < 1 || dof_b < 1 || !(c > 0.0)) {
    throw std::invalid_argument("ChiSquareSumCdf: need dofs >= 1 and c > 0, got " + std::to_string(dof_a) +
                                ", " + std::to_string(dof_b) + ", c " + std::to_string(c));
  }
  if (!(x > 0.0)) return 0.0;
  // Conditioning on B = u^2: P = int_0^sqrt(x/c) g(u) P(A <= x - c u^2) du
  // with g(u) = 2 u^(b-1) exp(-u^2/2) / (2^(b/2) Gamma(b/2)), B's density in
  // u; smooth for every b >= 1 (the substitution removes b = 1's pole).
  // Composite Simpson on 2000 panels is exact to about 1e-12 here.
  constexpr int kPanels = 2000;
  const double half_b = 0.5 * dof_b;
  const double norm = 2.0 / (std::pow(2.0, half_b) * std::tgamma(half_b));
  const double end = std::sqrt(x / c), h = end / kPanels;
  auto f = [&](double u) {
    return norm * std::pow(u, dof_b - 1) * std::exp(-0.5 * u * u) * ChiSquareCdf(dof_a, x - c * u * u);
  };
  double sum = f(0.0) + f(end);
  for (int k = 1; k < kPanels; ++k) sum += (k % 2 == 1 ? 4.0 : 2.0) * f(k * h);
  return std::clamp(sum * h / 3.0, 0.0, 1.0);
}

double ChordalCostCdf(int dimension, double x) {
  switch (dimension) {
    case 2: return ChiSquareSumCdf(2, 1, 2.0, x);
    case 3: return ChiSquareSumCdf(3, 3, 4.0, x);
  }
  throw std::invalid_argument("ChordalCostCdf: dimension must be 2 or 3, got " + std::to_string(dimension));
}

double ChordalCostQuantile(int dimension, double probability) {
  if ((dimension != 2 && dimension != 3) || !(probability > 0.0 && probability < 1.0)) {
    throw std::invalid_argument("ChordalCostQuantile: need dimension 2 or 3 and 0 < p < 1, got dimension " +
                                std::to_string(dimension) + ", p " + std::to_string(probability));
  }
  return Quantile([dimension](double x) { return ChordalCostCdf(dimension, x); }, 20.0, probability);
}

}  // namespace catgraph
