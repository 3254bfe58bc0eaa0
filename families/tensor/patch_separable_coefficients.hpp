#pragma once
// The stiffness coefficients of a tensor patch's geometry, fitted as products of univariate
// factors for its fast diagonalization: the tensor family's one patch, and each patch of a
// multipatch space.
#include "basis/core/geometry_map.hpp"
#include "basis/tensor/tensor_patch.hpp"
#include "solver/fast_diagonalization.hpp"

namespace knotwork {

// `geometry` is the patch's grid map (PatchGeometryMap with an ElementGrid of the whole
// patch). Empty (weights 1) when a midpoint Jacobian is not positive.
SeparableCoefficients patch_separable_coefficients(const TensorDiscretization& patch, const PatchGeometryMap& geometry);

}  // namespace knotwork
