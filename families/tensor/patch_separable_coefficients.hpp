#pragma once
// The stiffness coefficients of a tensor patch's or volume's geometry, fitted as products of
// univariate factors for its fast diagonalization and its multigrid's blocks: the tensor
// family's one patch, each patch of a multipatch space, and a volume.
#include "basis/core/geometry_map.hpp"
#include "basis/tensor/tensor_patch.hpp"
#include "solver/fast_diagonalization.hpp"
#include "solver/fast_diagonalization_3d.hpp"
#include "solver/poisson_problem.hpp"

namespace knotwork {

// `geometry` is the patch's grid map (PatchGeometryMap with an ElementGrid of the whole
// patch). Empty (weights 1) when a midpoint Jacobian is not positive. With `problem`, also the
// shift of its reaction term (its constant or its expression at the sampled midpoints): the
// fast diagonalization's, which sees no operator to read it off.
SeparableCoefficients patch_separable_coefficients(const TensorDiscretization& patch, const PatchGeometryMap& geometry,
                                                   const PoissonProblem* problem = nullptr);
// The same from the patch's map and its refined bases alone (no cell built: a process that does
// not hold the patch's cells).
SeparableCoefficients patch_separable_coefficients(const NurbsPatch& patch, const BSplineBasis1D& space_u,
                                                   const BSplineBasis1D& space_v, const PoissonProblem* problem = nullptr);

// How far the patch's stiffness coefficients C = |det J| J^-1 A J^-T (parameter derivatives;
// A the problem's diffusion, one expression or the three of a symmetric matrix, the identity
// when `diffusion` is empty) are from the best product of univariate factors that the fast
// diagonalization can use, P = diag(a1(u) b1(v), a2(u) b2(v)) (log c11 and log c22 fitted in
// least squares): over k x k points of the parameter domain, the largest eigenvalue of P^-1 C
// over the smallest. 1 for a separable map with A = 1 (the square, the annulus); a pointwise
// bound on the condition number of the fast diagonalization's preconditioned operator.
// Infinity where det J <= 0 or A is not positive definite at a point (the assembly refuses).
double separability_spread(const NurbsPatch& patch, const std::vector<Expression>& diffusion = {}, int k = 33);

// The volume's c_dd = |x_e x x_f|^2 / det J (parameter derivatives) at the midpoints of the
// space's elements, fitted (weights 1 where a Jacobian is not positive: the assembly refuses
// such maps first); with `problem`, the reaction's shift as above.
SeparableVolumeCoefficients volume_separable_coefficients(const TensorVolumeDiscretization& d,
                                                          const PoissonProblem* problem = nullptr);

}  // namespace knotwork
