#pragma once
// Geometric multigrid for the free dofs of a tensor-product spline space, as a preconditioner
// for CG (docs/SOLVERS.md, "multigrid").
//
// The hierarchy is the space's own uniform refinement read backwards: each coarser level
// drops every other breakpoint in each direction (nested spaces; the fine knots contain the
// coarse ones), the prolongation is the knot-insertion matrix P_v (x) P_u, and the coarse
// operators are Galerkin products P^T A P of the assembled fine matrix (whatever the form:
// geometry, coefficients, Nitsche terms). The smoother is block Gauss-Seidel on
// non-overlapping blocks of m x m functions, in two tilings shifted by m/2 and four colours
// each (same-coloured blocks do not couple, so a colour is solved at once, threaded). Each
// block is solved through the fast diagonalization of its principal block of the separable
// operator P = M_v^b1 (x) K_u^a1 + K_v^b2 (x) M_u^a2 (the geometry folded in as for the
// global preconditioner, with the same diagonal scaling): the local inverse of an m^2 block
// costs 4 m^3 flops and the two m x m eigenbases of its windows, so a smoothing sweep costs
// O(m) per dof and the setup O(m^2) per univariate function. Blocks that hold whole
// high-frequency modes are what keeps the smoother working as p grows, where a pointwise one
// fails (Hofreither and Takacs 2017; de la Riva, Rodrigo and Gaspar 2019).
#include <Eigen/SparseCore>
#include <memory>
#include <string>
#include <vector>

#include "basis/core/bspline_basis.hpp"
#include "solver/fast_diagonalization.hpp"
#include "solver/iterative_solver.hpp"
#include "solver/sparsity.hpp"
#include "solver/tensor_operator.hpp"

namespace knotwork {

struct TensorMultigridOptions {
  int block = 0;                  // functions per block side (at least 2p + 2); 0: max(16, 5p + 2)
  int coarsest_functions = 3000;  // coarsen while a level has more free dofs than this
  int tilings = 2;                // 1: the tiling at 0 only; 2: and the one shifted by block / 2
};

// What the hierarchy is, for notes and tests.
struct TensorMultigridReport {
  std::vector<long> free_dofs;  // per level, finest first; the last is solved by Cholesky
  int block = 0;
  int without_matrix = 0;  // the first levels, applied without a matrix (the variant below)
};

// The V-cycle (symmetric: the post-smoother sweeps the colours backwards) for the tensor space
// of space_u x space_v (function i + n_u j) and the free dofs of `layout`, whose matrix is
// `lower` (its lower triangle). Null when the free dofs are not a tensor product of free
// univariate ranges or a knot vector is not open (then it does not apply).
std::unique_ptr<Preconditioner> tensor_multigrid(const BSplineBasis1D& space_u, const BSplineBasis1D& space_v,
                                                 const DofLayout& layout, const Eigen::SparseMatrix<double>& lower,
                                                 const SeparableCoefficients& geometry = {},
                                                 const NitscheEnds& nitsche = {}, const TensorMultigridOptions& options = {},
                                                 TensorMultigridReport* report = nullptr);

// The same V-cycle without the fine matrix: the levels are the operator `op` rediscretized on
// the halved spaces (rediscretized_operator: the geometry moved to their elements), their
// smoothers' block residuals computed from the elements that touch each block, as long as the
// geometry lives on the coarser elements; the first level where it does not, and the coarsest,
// get their matrix by probing the operator, and Galerkin products below. On affine elements the
// quadrature is exact and the rediscretized operators are the Galerkin ones: the V-cycle is the
// one above. `free_diagonal`: K's diagonal over the free dofs. Null where the assembled one is
// null, or when the first coarser level cannot be rediscretized (that would store the matrix).
std::unique_ptr<Preconditioner> tensor_multigrid(std::shared_ptr<const TensorPoissonOperator> op, const DofLayout& layout,
                                                 const Eigen::VectorXd& free_diagonal, const SeparableCoefficients& geometry = {},
                                                 const TensorMultigridOptions& options = {},
                                                 TensorMultigridReport* report = nullptr);

// Its storage for `functions` functions of bi-degree (p, q): the whole matrix (both triangles,
// with indices), its coarse levels (a third more) and six vectors per level (for memory
// guards; measured 0.95-0.99 GB at 1M dofs and 3.9 GB at 4.2M, p = 2, whole runs).
// Without a matrix (with_matrix false): the six vectors per level, the first coarser level's
// net and the knot removal's dense copies of the fine net (24 bytes per function each).
double tensor_multigrid_bytes(double functions, int p, int q, bool with_matrix = true);

// The basis with every other breakpoint dropped (the odd ones, each with its multiplicity), the
// next coarser level of a uniform refinement; none when the number of elements is odd.
bool halved_basis(const BSplineBasis1D& fine, BSplineBasis1D& coarse);

}  // namespace knotwork
