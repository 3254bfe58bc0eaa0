#pragma once
#include <vector>

namespace knotwork {

// A one-dimensional quadrature rule on the reference interval [0, 1].
struct QuadratureRule1D {
  std::vector<double> nodes;    // increasing
  std::vector<double> weights;  // sum to 1
  int size() const { return static_cast<int>(nodes.size()); }
};

// n-point Gauss–Legendre rule on [0, 1]: exact for polynomials of degree <= 2n-1.
// Nodes and weights are accurate to a few ulp (Newton on the Legendre recurrence).
// Throws std::invalid_argument for n < 1 or n > 200.
QuadratureRule1D gauss_legendre(int n);

}  // namespace knotwork
