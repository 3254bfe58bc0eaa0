#pragma once
// The fast diagonalization preconditioner of a trivariate tensor-product space (Sangalli and
// Tani, 2016, in three directions): P = sum_d K_d^(tau_d) (x) prod_{k != d} M_k^(mu_k), plus
// shift prod_k M_k^(mu_k) for a reaction term, the parameter-domain operator with a separable
// part of the geometry folded in, inverted exactly through the generalized eigenvectors of the
// three univariate pairs (K_d^tau_d, M_d^mu_d), then scaled by D^{-1/2} on both sides,
// D = diag(K) / diag(P). One application costs three mode products forward and three back:
// 6 N (n_u + n_v + n_w) flops, O(N^(4/3)).
//
// The geometry enters through the diagonal of the stiffness coefficients C = det(J) J^-1 J^-T
// in parameter derivatives, c_dd = |x_e x x_f|^2 / det J ({d, e, f} = {u, v, w}), approximated
// as c_dd ~ tau_d(x_d) prod_{k != d} mu_k(x_k), one value per element: the form in which the
// mass in direction k is the same in the two terms that carry it, as the eigenvectors need.
// It is exact for the box (constants). For the thick annulus, where c_vv carries 1/r and
// c_ww carries r, the two estimates of mu_u disagree by the ratio of the radii, and the fit
// takes their geometric mean: P stays spectrally equivalent to K, and CG's iterations stay
// bounded in h (docs/SOLVERS.md).
#include <array>
#include <functional>
#include <memory>
#include <vector>

#include "basis/core/bspline_basis.hpp"
#include "solver/fast_diagonalization.hpp"

namespace knotwork {

// tau[d] and mu[d]: one value per element of direction d; empty: weights 1 (no geometry).
struct SeparableVolumeCoefficients {
  std::array<std::vector<double>, 3> tau, mu;
  // A reaction term c u as shift (M_u^mu (x) M_v^mu (x) M_w^mu), the identity in the
  // eigenbases: shift ~ c det J / (mu_u mu_v mu_w), averaged (volume_separable_coefficients).
  // 0: none. The fast diagonalization reads it; the multigrids read theirs off each level's
  // operator instead.
  double shift = 0;
  // c(i, j, k) = {c_uu, c_vv, c_ww} at element (i, j, k) of an n[0] x n[1] x n[2] grid, fitted
  // on log c from the elements of up to 8 sampled lines in the other two directions for each
  // element of each direction (O(n) evaluations, not n^3). Exact for c of the form above.
  static SeparableVolumeCoefficients fit(const std::array<int, 3>& n,
                                         const std::function<std::array<double, 3>(int, int, int)>& c);
};

// The free univariate indices of each direction when the free dofs of `layout` (over the
// functions i + n_u j + n_u n_v k) are their tensor product numbered a + |I_u| (b + |I_v| c);
// false otherwise.
bool tensor_free_indices_3d(const std::array<int, 3>& n, const DofLayout& layout, std::array<std::vector<int>, 3>& free);

// Its storage for n_u x n_v x n_w functions: the eigenvectors, the inverse eigenvalue sums and
// two work tensors (for memory guards).
inline double fast_diagonalization_3d_bytes(const std::array<double, 3>& n) {
  return (n[0] * n[0] + n[1] * n[1] + n[2] * n[2] + 4 * n[0] * n[1] * n[2]) * 8;
}

// For the tensor space of `spaces` (function i + n_u j + n_u n_v k) and the free dofs of
// `layout`: the preconditioner, or null when the free functions are not a tensor product of
// free univariate ones. `diagonal`: the assembled matrix's, one entry per dof (the scaling).
// `nitsche`: the faces (u = 0, u = 1, v = 0, v = 1, w = 0, w = 1) whose Dirichlet data
// Nitsche's method imposes, which add the 1D Nitsche terms to their direction's stiffness.
std::unique_ptr<Preconditioner> fast_diagonalization_3d(const std::array<BSplineBasis1D, 3>& spaces, const DofLayout& layout,
                                                        const Eigen::VectorXd& diagonal,
                                                        const SeparableVolumeCoefficients& geometry = {},
                                                        const std::array<bool, 6>& nitsche = {}, double nitsche_factor = 2);

}  // namespace knotwork
