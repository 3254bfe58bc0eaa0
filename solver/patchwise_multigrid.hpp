#pragma once
// Geometric multigrid for a space of tensor-product patches glued C^0 along whole sides, as a
// preconditioner for CG (docs/SOLVERS.md, "On several patches").
//
// The levels are the space's uniform refinements read backwards, each a space of the same
// patches with half the elements (the family builds them). A coarse function's fine
// coefficients come patch by patch from knot insertion; on an interface both patches give the
// same ones, because both refine that edge alike. Coarse operators are Galerkin products
// P^T A P of the assembled fine matrix. The smoother has two parts:
//   1. every patch's interior functions (on no interface, not fixed), by the one-patch
//      multigrid's block Gauss-Seidel (solver/tensor_multigrid.hpp): blocks of m x m functions
//      in two shifted tilings and four colours, each solved through the fast diagonalization of
//      the patch's separable operator. Interior functions of two patches never share a cell, so
//      a colour runs over all patches at once;
//   2. the functions on the interfaces and within `strip_layers` of them, solved exactly by a
//      sparse Cholesky factor of their principal block of A. A block cannot straddle two
//      patches whose separable fits differ; the strip is a band along the interfaces, whose
//      factor costs about its size times its width squared.
// The blocks keep the smoother robust in p inside each patch (as on one patch); the exact
// strip keeps it so where patches meet. The post-smoother runs the steps backwards, so the
// V-cycle is symmetric.
#include <Eigen/SparseCore>
#include <memory>
#include <vector>

#include "basis/core/bspline_basis.hpp"
#include "solver/fast_diagonalization.hpp"
#include "solver/iterative_solver.hpp"
#include "solver/sparsity.hpp"

namespace knotwork {

struct PatchwiseMultigridOptions {
  int block = 0;           // functions per block side (at least 2p + 2); 0: max(16, 5p + 2)
  int tilings = 2;         // 1: the tiling at 0 only; 2: and the one shifted by block / 2
  int strip_layers = -1;   // interior functions per side beside the interface ones; -1: the degree
};

struct PatchwiseMultigridReport {
  std::vector<long> free_dofs;   // per level, finest first; the last is solved by Cholesky
  std::vector<long> strip_dofs;  // per level but the coarsest: the functions the strip solves
  int block = 0;
};

// One patch of one level.
struct MultigridPatch {
  BSplineBasis1D u, v;
  SeparableCoefficients geometry;  // its separable fit; empty: the parameter domain's
  NitscheEnds nitsche;             // its sides whose Dirichlet data Nitsche's method imposes
  std::vector<int> function;       // its function i + n_u j -> the level's function
};

struct PatchwiseLevel {
  std::vector<MultigridPatch> patches;
  DofLayout layout;  // the level's functions -> its free dofs
  // From the next coarser level's free dofs to this level's (rows: this level's free dofs);
  // link_coarser sets it, empty on the coarsest.
  Eigen::SparseMatrix<double, Eigen::RowMajor> prolongation;
};

// Sets coarse.layout and fine.prolongation. A coarse function is fixed when its refinement
// reaches a fixed function of `fine` (a strongly imposed Dirichlet side's functions refine into
// that side's functions and interior ones; an interior function into interior ones only).
// std::invalid_argument when the levels' patches differ in number or a coarse patch's space is
// not contained in its fine one.
void link_coarser(PatchwiseLevel& fine, PatchwiseLevel& coarse);

// A fine patch's separable fit on a coarser patch's elements (whose breakpoints are among the
// fine ones): each coarse element's weight the geometric mean of those of the fine elements in
// it, as the fit is log-linear.
SeparableCoefficients coarser_fit(const MultigridPatch& fine, const BSplineBasis1D& coarse_u, const BSplineBasis1D& coarse_v);

// The V-cycle, finest level first (each linked to the next by link_coarser); `lower` is the
// finest level's matrix over its free dofs (its lower triangle, as CHOLMOD reads it). Null
// when a patch's interior functions on some level are not a box (a patch side that is partly
// on an interface, say): the smoother's blocks need a box.
std::unique_ptr<Preconditioner> patchwise_multigrid(std::vector<PatchwiseLevel> levels,
                                                    const Eigen::SparseMatrix<double>& lower,
                                                    const PatchwiseMultigridOptions& options = {},
                                                    PatchwiseMultigridReport* report = nullptr);

}  // namespace knotwork
