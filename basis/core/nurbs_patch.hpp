#pragma once
#include <Eigen/Core>

#include "basis/core/bspline_basis.hpp"

namespace knotwork {

// A single NURBS patch: open knot vectors in u and v, control points numbered
// i + n_u * j (u fastest), positive weights.
struct NurbsPatch {
  BSplineBasis1D basis_u, basis_v;
  Eigen::MatrixX2d control_points;
  Eigen::VectorXd weights;
  // Throws std::invalid_argument naming what is wrong (counts, weights, open knots).
  void validate() const;
};

// Throws std::invalid_argument naming the first control point that is not finite or weight that
// is not a positive finite number (a patch's net or a volume's).
void validate_net(const Eigen::Ref<const Eigen::MatrixXd>& control_points, const Eigen::VectorXd& weights);

// The patch's point at parameters (u, v).
Eigen::Vector2d patch_point(const NurbsPatch& patch, double u, double v);

// The point, its derivatives (columns x_u, x_v) and the weight function's value at (u, v).
struct PatchPointDerivatives {
  Eigen::Vector2d x;
  Eigen::Matrix2d jacobian;
  double weight = 1;
};
PatchPointDerivatives patch_point_derivatives(const NurbsPatch& patch, double u, double v);

}  // namespace knotwork
