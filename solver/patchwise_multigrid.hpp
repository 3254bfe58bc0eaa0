#pragma once
// Geometric multigrid for a space of tensor-product patches (planar patches or volumes) glued
// C^0 along whole sides or faces, as a preconditioner for CG (docs/SOLVERS.md, "On several
// patches"; docs/VOLUMES.md).
//
// The levels: every patch's bases with every other breakpoint dropped (halved_basis), again and
// again. A coarse function's fine coefficients come patch by patch from knot insertion; on an
// interface both patches give the same ones, because both refine it alike, so the coarse
// functions of two patches that are one glued function are found by their coefficients on the
// fine interface functions (the same trace), with no help from the family. Coarse operators
// are Galerkin products P^T A P of the assembled fine matrix. The smoother has two parts:
//   1. every patch's interior functions (on no interface, not fixed), by the one-patch
//      multigrid's block Gauss-Seidel (solver/tensor_multigrid.hpp): blocks of m^d functions in
//      two shifted tilings and 2^d colours, each solved through the fast diagonalization of the
//      patch's separable operator. Interior functions of two patches never share a cell, so a
//      colour runs over all patches at once;
//   2. the functions on the interfaces and within `strip_layers` of them (a band), solved
//      exactly by a sparse Cholesky factor (CHOLMOD) of their principal block of A. A block
//      cannot straddle two patches whose separable fits differ; the band can be solved whole.
// The blocks keep the smoother robust in p inside each patch (as on one patch); the exact band
// keeps it so where patches meet. The post-smoother runs the steps backwards, so the V-cycle
// is symmetric.
#include <Eigen/SparseCore>
#include <array>
#include <memory>
#include <vector>

#include "basis/core/bspline_basis.hpp"
#include "solver/fast_diagonalization.hpp"
#include "solver/fast_diagonalization_3d.hpp"
#include "solver/iterative_solver.hpp"
#include "solver/sparsity.hpp"

namespace knotwork {

struct PatchwiseMultigridOptions {
  int block = 0;                  // functions per block side (at least 2p + 2); 0: max(16, 5p + 2)
  int tilings = 2;                // 1: the tiling at 0 only; 2: and the one shifted by block / 2
  int strip_layers = -1;          // interior functions per side beside the interface ones; -1: the degree
  int coarsest_functions = 3000;  // coarsen while a level has more free dofs than this
};

struct PatchwiseMultigridReport {
  std::vector<long> free_dofs;   // per level, finest first; the last is factored
  std::vector<long> strip_dofs;  // per level but the coarsest: the functions the band solves
  int block = 0;
};

// One patch of one level.
struct MultigridPatch {
  std::vector<BSplineBasis1D> bases;  // u, v (and w on a volume)
  // Per direction: the separable fit's weights of its mass and stiffness per element (empty: 1).
  std::vector<std::vector<double>> mass_weight, stiffness_weight;
  // Per direction: whether Nitsche's method imposes Dirichlet data at its start and its end.
  std::vector<std::array<bool, 2>> nitsche;
  double nitsche_factor = 2;
  std::vector<int> function;  // its function a + n_u (b + n_v c) -> the level's function
};

// A planar patch with its separable fit (fast_diagonalization.hpp: u takes a1 as stiffness and
// a2 as mass, v b2 and b1) and Nitsche sides (bottom, right, top, left).
MultigridPatch planar_multigrid_patch(const BSplineBasis1D& u, const BSplineBasis1D& v, const SeparableCoefficients& fit,
                                      const NitscheEnds& nitsche, std::vector<int> function);
// A volume with its separable fit (direction k: stiffness tau[k], mass mu[k]) and the faces
// whose Dirichlet data Nitsche's method imposes (u = 0, u = 1, v = 0, v = 1, w = 0, w = 1).
MultigridPatch volume_multigrid_patch(const std::array<BSplineBasis1D, 3>& bases, const SeparableVolumeCoefficients& fit,
                                      std::vector<int> function, const std::array<bool, 6>& nitsche = {},
                                      double nitsche_factor = 2);

struct PatchwiseLevel {
  std::vector<MultigridPatch> patches;
  DofLayout layout;  // the level's functions -> its free dofs
  // From the next coarser level's free dofs to this level's (rows: this level's free dofs);
  // coarser_level sets it, empty on the coarsest.
  Eigen::SparseMatrix<double, Eigen::RowMajor> prolongation;
};

// The next coarser level of `fine` and fine.prolongation; false (and nothing set) when some
// patch's basis does not halve (an odd number of elements). The coarse functions are numbered
// patch by patch, a glued one where it first occurs; one is fixed when its refinement reaches a
// fixed function of `fine` (a strongly imposed Dirichlet side's functions refine into that
// side's functions and interior ones; an interior function into interior ones only). The fits
// are fine's, each coarse element's weight the geometric mean of the fine elements' in it.
// std::logic_error when two patches' refinements of what should be one glued function differ
// (a non-conforming interface).
bool coarser_level(PatchwiseLevel& fine, PatchwiseLevel& coarse);

// The V-cycle over `finest` and its coarser levels (while a level has more than
// options.coarsest_functions free dofs and can be halved); `lower` is the finest level's matrix
// over its free dofs (its lower triangle, as CHOLMOD reads it). Null when a patch's interior
// functions on some level are not a box (a side that is partly on an interface, say): the
// smoother's blocks need a box.
std::unique_ptr<Preconditioner> patchwise_multigrid(PatchwiseLevel finest, const Eigen::SparseMatrix<double>& lower,
                                                    const PatchwiseMultigridOptions& options = {},
                                                    PatchwiseMultigridReport* report = nullptr);

}  // namespace knotwork
