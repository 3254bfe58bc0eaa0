#pragma once
// The fast diagonalization preconditioner (Sangalli and Tani, 2016) of a tensor-product
// space: the Laplacian of the parameter domain, M_v (x) K_u + K_v (x) M_u, inverted exactly
// through the generalized eigenvectors of the univariate pairs (K_u, M_u) and (K_v, M_v),
// then scaled by D^{-1/2} on both sides, D = diag(K) / diag(P), which folds in the
// geometry's local size and aspect (their "diagonal scaling").
#include <Eigen/SparseCore>
#include <memory>
#include <vector>

#include "basis/core/bspline_basis.hpp"
#include "solver/iterative_solver.hpp"
#include "solver/sparsity.hpp"

namespace knotwork {

// The univariate mass and stiffness matrices of a B-spline basis on its parameter domain
// (dense; Gauss quadrature with p + 1 points per element: exact).
void univariate_mass_stiffness(const BSplineBasis1D& b, Eigen::MatrixXd& mass, Eigen::MatrixXd& stiffness);

// For the tensor space of space_u x space_v (function i + n_u j) and the free dofs of
// `layout`: the preconditioner, or null when the free functions are not a tensor product of
// free univariate ones (then it does not apply). `lower` is the assembled matrix (its
// diagonal gives the scaling).
std::unique_ptr<Preconditioner> fast_diagonalization(const BSplineBasis1D& space_u, const BSplineBasis1D& space_v,
                                                     const DofLayout& layout, const Eigen::SparseMatrix<double>& lower);

}  // namespace knotwork
