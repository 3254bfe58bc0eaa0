#pragma once
// The source of -div_G(A grad_G u) + c u = f on a surface, derived from an exact solution u
// of (x, y, z) on the discrete surface itself, so that the discrete surface's problem has u as
// its solution (PoissonForm::source null). Needs u's ambient gradient and Hessian, the
// surface's first and second derivatives, and A's ambient derivatives.
#include <Eigen/Core>
#include <optional>
#include <vector>

#include "solver/expression.hpp"

namespace knotwork {

// What the tangential divergence needs of the surface at one point: x_u, x_v, x_uu, x_uv, x_vv.
struct SurfaceFrame {
  Eigen::Vector3d xu, xv, xuu, xuv, xvv;
};

// div_G(P A P g) at a point of the surface, P = I - n n^T the tangent projection, for an
// ambient vector field g = grad u with ambient derivative H (the Hessian) and an ambient matrix
// field A with partial derivatives dA[0..2] (by x, y, z). Differentiates P along the surface
// (through the normal's derivatives n_u, n_v), so it is exact for the discrete surface.
double tangential_divergence(const SurfaceFrame& s, const Eigen::Vector3d& g, const Eigen::Matrix3d& H,
                             const Eigen::Matrix3d& A, const Eigen::Matrix3d dA[3]);

// f at the quadrature points of a surface cell. The coefficient A is the identity (no
// entries), a scalar a (one entry: -a Laplace_Beltrami(u) - grad(a).P grad(u)) or a symmetric
// 3x3 matrix (six entries a11 a12 a13 a22 a23 a33, of which only the tangential part P A P
// acts); each entry comes with its ambient derivatives (differentiate_surface_solution). c is
// the constant `reaction` unless `variable_reaction` is given. Not thread-safe: one per thread.
class DerivedSurfaceSource {
 public:
  DerivedSurfaceSource(const ExactSolution& u, const std::vector<ExactSolution>& coefficient,
                       const Expression* variable_reaction, double reaction);
  // x: points x 3, J: points x 6 (x_u x_v y_u y_v z_u z_v), second: points x 9 (x_uu, x_uv, x_vv
  // per coordinate).
  void operator()(const Eigen::MatrixXd& x, const Eigen::MatrixXd& J, const Eigen::MatrixXd& second,
                  Eigen::VectorXd& out);

 private:
  ExpressionEvaluator value_;
  std::vector<ExpressionEvaluator> gradient_, hessian_;  // hessian: xx, xy, xz, yy, yz, zz
  std::vector<ExpressionEvaluator> coefficient_;         // per entry: value, d/dx, d/dy, d/dz
  int entries_ = 0;
  std::optional<ExpressionEvaluator> variable_reaction_;
  double reaction_ = 0;
};

}  // namespace knotwork
