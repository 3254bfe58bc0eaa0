#include "quadrature/gauss_legendre.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace knotwork {

QuadratureRule1D gauss_legendre(int n) {
  if (n < 1 || n > 200)
    throw std::invalid_argument("gauss_legendre: number of points must be in [1, 200], got " +
                                std::to_string(n));
  QuadratureRule1D rule;
  rule.nodes.resize(n);
  rule.weights.resize(n);
  // Roots of P_n on [-1,1] are symmetric: find the upper half by Newton's method
  // from the Tricomi-type initial guess, then mirror.
  for (int i = 0; i < (n + 1) / 2; ++i) {
    double z = std::cos(std::numbers::pi * (i + 0.75) / (n + 0.5));
    double dp = 0.0;
    for (int iter = 0; iter < 100; ++iter) {
      double p0 = 1.0, p1 = 0.0;
      for (int k = 1; k <= n; ++k) {  // three-term recurrence for P_k(z)
        const double p2 = p1;
        p1 = p0;
        p0 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p2) / k;
      }
      dp = n * (z * p0 - p1) / (z * z - 1.0);
      const double dz = p0 / dp;
      z -= dz;
      if (std::abs(dz) < 1e-16) break;
    }
    // Recompute the derivative at the converged root for the weight.
    double p0 = 1.0, p1 = 0.0;
    for (int k = 1; k <= n; ++k) {
      const double p2 = p1;
      p1 = p0;
      p0 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p2) / k;
    }
    dp = n * (z * p0 - p1) / (z * z - 1.0);
    const double w = 2.0 / ((1.0 - z * z) * dp * dp);
    // Map [-1,1] -> [0,1]: x = (1+z)/2, weight halves.
    rule.nodes[i] = 0.5 * (1.0 - z);
    rule.nodes[n - 1 - i] = 0.5 * (1.0 + z);
    rule.weights[i] = rule.weights[n - 1 - i] = 0.5 * w;
  }
  if (n % 2 == 1) rule.nodes[n / 2] = 0.5;
  return rule;
}

}  // namespace knotwork
