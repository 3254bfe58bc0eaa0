#pragma once
#include <Eigen/Core>
#include <vector>

#include "basis/core/bezier_mesh.hpp"
#include "basis/core/geometry_map.hpp"
#include "solver/poisson_problem.hpp"

namespace knotwork {

// Residual a posteriori error indicators for -div(A grad u) + c u = f (the standard estimator of
// adaptive FEM/IGA), per cell K:
//   eta_K^2 = h_K^2 ||f + div(A grad u_h) - c u_h||^2_K
//           + 1/2 sum over interior edges E of K of h_E ||[A grad u_h]||^2_E
//           + sum over Neumann edges E of K of h_E ||g - (A grad u_h).n||^2_E
//           + sum over Dirichlet edges E of K imposed by Nitsche's method of h_E^-1 ||g - u_h||^2_E
// with h the physical cell diameter and edge length. The last term is what the weakly imposed
// trace misses g by (Becker, Hansbo and Stenberg 2003); strongly imposed sides have none. u_h
// is continuous, so the jump of the normal derivative is the jump of the whole gradient; on
// C^1 edges it vanishes (up to roundoff) and only the C^0 ones (e.g. the L-shape's fold)
// contribute.
struct ErrorIndicators {
  Eigen::VectorXd eta_squared;  // per cell
  double residual_part = 0, jump_part = 0, neumann_part = 0, dirichlet_part = 0;  // sums of the terms
  double max_gradient_jump = 0;                               // largest |[grad u_h]| seen
  double total() const { return eta_squared.sum(); }
};

// Needs a planar or volume, polynomial BezierMesh with its cell interfaces (BezierMesh::interfaces,
// built by the family: one patch or many, planar multi-patch meshes included; on hexahedra the
// face pieces) and a geometry with second derivatives; throws std::invalid_argument otherwise.
// On hexahedra, edges read faces: h_E is a face piece's diameter (residual_estimator_volume.cpp).
ErrorIndicators residual_indicators(const BezierMesh& mesh, const GeometryMap& geometry,
                                    const Eigen::VectorXd& coefficients, const PoissonProblem& problem);
// The same on hexahedra (residual_indicators calls it for volumes).
ErrorIndicators volume_residual_indicators(const BezierMesh& mesh, const GeometryMap& geometry,
                                           const Eigen::VectorXd& coefficients, const PoissonProblem& problem);

// How the loop chooses what to refine from the indicators eta^2 (of cells, or of functions).
// - Doerfler (bulk): the fewest items, largest first, whose eta^2 add up to at least theta
//   times the total.
// - Maximum: every item whose eta is at least theta times the largest eta.
// Either way, at least min_fraction of all items (largest first) are marked, so that a loop
// whose markings stay local (a corner singularity) still grows the space by a fixed factor per
// step and needs O(log N) steps. theta in (0, 1], min_fraction in [0, 1].
struct Marking {
  enum class Strategy { kDorfler, kMaximum } strategy = Strategy::kDorfler;
  double theta = 0.5;
  double min_fraction = 0;
};

// The marked items, largest indicator first (ties: the lower index first).
std::vector<int> mark(const Eigen::VectorXd& eta_squared, const Marking& marking);

// Marking of functions, as hierarchical codes do: a function's indicator is the sum of eta_K^2
// over the cells it lives on; the functions are marked as `marking` says, and the cells of
// their supports returned (sorted).
std::vector<int> cells_of_marked_functions(const BezierMesh& mesh, const Eigen::VectorXd& eta_squared,
                                           const Marking& marking);

}  // namespace knotwork
