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
  // Entries: none (A = I), one (a I), three (a11, a12, a22) in the plane, or six (a11, a12, a13,
  // a22, a23, a33) in space.
  explicit DiffusionAtPoints(const std::vector<Expression>& diffusion);
  bool identity() const { return entries_.empty(); }
  Eigen::Matrix2d operator()(double x, double y);
  // In space (a volume's faces): A at (x, y, z) from none, one or six entries.
  Eigen::Matrix3d operator()(double x, double y, double z);

 private:
  std::vector<ExpressionEvaluator> entries_;
};

}  // namespace knotwork
