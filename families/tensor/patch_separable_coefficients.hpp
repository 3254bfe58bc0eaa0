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

// The volume's c_dd = |x_e x x_f|^2 / det J (parameter derivatives) at the midpoints of the
// space's elements, fitted (weights 1 where a Jacobian is not positive: the assembly refuses
// such maps first); with `problem`, the reaction's shift as above.
SeparableVolumeCoefficients volume_separable_coefficients(const TensorVolumeDiscretization& d,
                                                          const PoissonProblem* problem = nullptr);

}  // namespace knotwork
