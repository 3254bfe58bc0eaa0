#pragma once
// Tensor-product B-splines and NURBS on a multipatch domain, C0-conforming across its
// interfaces: every patch refined as build_tensor_discretization refines one, the knots along
// every interface compared, and the functions of two glued sides identified by their traces
// (glue_patches).
#include <vector>

#include "basis/core/multipatch.hpp"
#include "basis/tensor/tensor_patch.hpp"

namespace knotwork {

struct MultiPatchTensorDiscretization {
  BezierMesh mesh;  // the patches' cells in patch order; cell.patch is the patch's index
  std::vector<TensorDiscretization> patches;  // each patch's own space (its functions numbered locally)
  std::vector<int> first_cell;                // patch k's cells are first_cell[k] .. first_cell[k+1]-1
  std::vector<std::vector<int>> global_function;  // per patch: its function i -> the shared numbering
};

// Throws std::invalid_argument for options no patch can take (as build_tensor_discretization),
// and GeometryError naming the interface (its `where`) when the refined spaces of its two sides
// differ (another degree, other knots or continuities along it: a non-conforming refinement)
// or their weights differ. The mesh's boundary ids are exterior_sides(domain), named "P:S".
MultiPatchTensorDiscretization build_multipatch_tensor(const MultiPatch& domain, const TensorSpaceOptions& options);

}  // namespace knotwork
