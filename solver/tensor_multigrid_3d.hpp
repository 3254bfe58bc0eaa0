#pragma once
// Geometric multigrid for the free dofs of a trivariate tensor-product spline space, as a
// preconditioner for CG: the bivariate one (tensor_multigrid.hpp) in three directions
// (docs/SOLVERS.md, "multigrid"). The hierarchy drops every other breakpoint per direction, the
// prolongation is P_w (x) P_v (x) P_u (knot insertion), the coarse operators are the Galerkin
// products P^T A P of the assembled matrix, one direction at a time. The smoother is block
// Gauss-Seidel on m x m x m blocks of functions in two tilings shifted by m/2 and eight colours
// each, every block solved through the fast diagonalization of its principal block of the
// separable operator sum_d K_d^tau_d (x) prod_(k != d) M_k^mu_k (the geometry fit of
// fast_diagonalization_3d.hpp, with its diagonal scaling): 6 m flops per dof and block.
#include <Eigen/SparseCore>
#include <array>
#include <memory>

#include "basis/core/bspline_basis.hpp"
#include "solver/affine_volume_operator.hpp"
#include "solver/fast_diagonalization_3d.hpp"
#include "solver/tensor_multigrid.hpp"

namespace knotwork {

// The symmetric V-cycle for the space of `spaces` (function i + n_u (j + n_v k)) and the free
// dofs of `layout`, whose matrix is `lower` (its lower triangle). `nitsche`: the faces (u = 0,
// u = 1, v = 0, v = 1, w = 0, w = 1) whose Dirichlet data Nitsche's method imposes (the blocks'
// separable operator gets their 1D terms). Null when the free dofs are not a tensor product
// of free univariate ranges or a knot vector is not open.
std::unique_ptr<Preconditioner> tensor_multigrid_3d(const std::array<BSplineBasis1D, 3>& spaces, const DofLayout& layout,
                                                    const Eigen::SparseMatrix<double>& lower,
                                                    const SeparableVolumeCoefficients& geometry = {},
                                                    const std::array<bool, 6>& nitsche = {}, double nitsche_factor = 2,
                                                    const TensorMultigridOptions& options = {},
                                                    TensorMultigridReport* report = nullptr);

// The same V-cycle without the fine matrix, on a volume that is one affine map: each level is
// the operator on its halved spaces (exact there: the Galerkin operator of nested spaces), its
// residuals by mode products, the smoother's over each block's reach; the coarsest level's
// matrix written by its operator. `free_diagonal`: K's diagonal over the free dofs.
std::unique_ptr<Preconditioner> tensor_multigrid_3d(std::shared_ptr<const AffineVolumeOperator> op, const DofLayout& layout,
                                                    const Eigen::VectorXd& free_diagonal,
                                                    const SeparableVolumeCoefficients& geometry = {},
                                                    const TensorMultigridOptions& options = {},
                                                    TensorMultigridReport* report = nullptr);

// Its storage for `functions` functions of degree (p, q, r) (for memory guards): the whole
// matrix (both triangles, with indices) and its coarse levels (an eighth more per level), six
// vectors per level; without a matrix (with_matrix false), seven vectors per level.
double tensor_multigrid_3d_bytes(double functions, const std::array<int, 3>& degree, bool with_matrix);

}  // namespace knotwork
