#pragma once
// The coefficient A of -div(A grad u) + c u at single points (boundary fluxes, Nitsche's
// conormal derivative and penalty bound, the residual estimator), read from the entries of
// PoissonCoefficients::diffusion. Not thread-safe (its evaluators are not): one per thread.
#include <Eigen/Core>
#include <vector>

#include "solver/expression.hpp"

namespace knotwork {

class DiffusionAtPoints {
 public:
  // Entries: none (A = I), one (a I) or three (a11, a12, a22).
  explicit DiffusionAtPoints(const std::vector<Expression>& diffusion);
  bool identity() const { return entries_.empty(); }
  Eigen::Matrix2d operator()(double x, double y);

 private:
  std::vector<ExpressionEvaluator> entries_;
};

}  // namespace knotwork
