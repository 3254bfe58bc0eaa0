#pragma once
// The fast diagonalization preconditioner (Sangalli and Tani, 2016) of a tensor-product
// space: P = M_v^b1 (x) K_u^a1 + K_v^b2 (x) M_u^a2, the parameter-domain operator with the
// separable part of the geometry folded in, inverted exactly through the generalized
// eigenvectors of the univariate pairs (K_u^a1, M_u^a2) and (K_v^b2, M_v^b1), then scaled by
// D^{-1/2} on both sides, D = diag(K) / diag(P) (their "diagonal scaling"). The weights
// come from the stiffness coefficients c11 = |x_v|^2 / det J and c22 = |x_u|^2 / det J of
// the geometry (parameter derivatives), fitted as c11 ~ a1(u) b1(v), c22 ~ a2(u) b2(v)
// element by element (SeparableCoefficients); exact for maps such as the annulus, whose
// coefficients separate, where CG then converges in a few iterations.
#include <Eigen/SparseCore>
#include <array>
#include <memory>
#include <vector>

#include "basis/core/bspline_basis.hpp"
#include "solver/iterative_solver.hpp"
#include "solver/sparsity.hpp"

namespace knotwork {

// One direction of a separable operator: the univariate mass and stiffness matrices of a
// B-spline basis on its parameter domain (Gauss quadrature with p + 1 points per element:
// exact), each weighted by a constant per element (in element_spans() order; empty: weight 1),
// the stiffness with the 1D Nitsche terms (NitscheEnds) at the ends asked for. Sparse: 2p + 1
// diagonals.
struct UnivariatePair {
  Eigen::SparseMatrix<double> mass, stiffness;
};
UnivariatePair univariate_pair(const BSplineBasis1D& b, const std::vector<double>& mass_weight = {},
                               const std::vector<double>& stiffness_weight = {}, bool nitsche_start = false,
                               bool nitsche_end = false, double nitsche_factor = 2);

// The geometry's stiffness coefficients as products of univariate factors, one value per
// element and direction: c11(i, j) ~ a1[i] b1[j], c22(i, j) ~ a2[i] b2[j], fitted by least
// squares on log c (exact when c separates). Empty: no geometry (weights 1).
// P = M_v^b1 (x) K_u^a1 + K_v^b2 (x) M_u^a2 + shift M_v^b1 (x) M_u^a2.
struct SeparableCoefficients {
  std::vector<double> a1, b1, a2, b2;
  // A reaction term c u as shift (M_u^a2 (x) M_v^b1), the one mass product the eigenvectors
  // diagonalize (the identity in the eigenbases): shift ~ c det J / (a2 b1), averaged
  // (patch_separable_coefficients). 0: none. The fast diagonalization reads it; the multigrids
  // read theirs off each level's operator instead.
  double shift = 0;
  // From c11 and c22 at element (i, j), stored at i + n_u j. With `rows` I and `columns` J
  // (empty: all), only the cells (i, j in J) and (i in I, j) are read: a1[i] from row i's
  // cells in J, b1[j] from column j's cells in I (still exact for separable c).
  static SeparableCoefficients fit(int n_u, int n_v, const std::vector<double>& c11, const std::vector<double>& c22,
                                   std::vector<int> rows = {}, std::vector<int> columns = {});
};

// The sides (bottom v = 0, right u = 1, top v = 1, left u = 0) whose Dirichlet data are
// imposed by Nitsche's method, and its penalty factor (PoissonProblem::nitsche_penalty).
// Each adds to the univariate stiffness of its direction the 1D Nitsche terms at its end,
// weighted like that direction's stiffness on the end element:
//   -+ w (N_i' N_k + N_i N_k') + factor 2 w p^2 / h N_i N_k   (- at the start, + at the end),
// p^2 / h the largest |v'(end)|^2 / int |v'|^2 over the end element's polynomials: the 1D
// form is coercive for factor > 1 as the 2D one is.
struct NitscheEnds {
  std::array<bool, 4> sides{};
  double factor = 2;
};

// The free univariate indices of each direction, when the free dofs of `layout` (over the
// functions i + nu j) are their tensor product, numbered a + |iu| b; false otherwise.
bool tensor_free_indices(int nu, int nv, const DofLayout& layout, std::vector<int>& iu, std::vector<int>& iv);

// What the 2D and 3D preconditioners share. diagonalize: K of `pair` restricted to the indices
// `keep`, and its generalized eigenvectors U (U^T M U = I, U^T K U = diag(lambda)), by LAPACK's
// dsygvd; std::runtime_error if M is not positive definite there. blas_gemm: C = op(A) op(B),
// column-major with leading dimensions, through the BLAS's dgemm.
void diagonalize(const UnivariatePair& pair, const std::vector<int>& keep, Eigen::MatrixXd& U, Eigen::VectorXd& lambda);
void blas_gemm(bool transpose_a, bool transpose_b, int m, int n, int k, const double* A, int lda, const double* B, int ldb,
               double* C, int ldc);

// Its storage for n_u x n_v functions: the eigenvectors and a product's workspace, four dense
// n x n arrays per direction (for memory guards).
inline double fast_diagonalization_bytes(double n_u, double n_v) { return 4 * (n_u * n_u + n_v * n_v) * 8; }

// For the tensor space of space_u x space_v (function i + n_u j) and the free dofs of
// `layout`: the preconditioner, or null when the free functions are not a tensor product of
// free univariate ones (then it does not apply). `diagonal`: the assembled matrix's, one entry
// per dof of `layout` (the scaling; an entry <= 0 leaves its dof unscaled).
std::unique_ptr<Preconditioner> fast_diagonalization(const BSplineBasis1D& space_u, const BSplineBasis1D& space_v,
                                                     const DofLayout& layout, const Eigen::VectorXd& diagonal,
                                                     const SeparableCoefficients& geometry = {},
                                                     const NitscheEnds& nitsche = {});

}  // namespace knotwork
