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

// One process's part of that space (under mpirun): rank r of R owns a contiguous run of whole
// patches (balanced by cells) and the functions numbered first in them, which are one
// contiguous run of the global numbering (functions are numbered patch by patch, a shared one
// where it first occurs). The mesh holds the owned patches' cells, then the cells of later
// patches on which owned functions live (the halo along their interfaces), with the functions
// on those cells numbered locally in increasing global order (part.global_function). Every
// rank numbers all functions from the patches' univariate bases, and builds the cells of
// the patches it owns or takes halo cells from only. std::invalid_argument when there are
// fewer patches than ranks; GeometryError as build_multipatch_tensor.
struct MultiPatchTensorPart {
  BezierMesh mesh;
  MeshPart part;
  std::vector<int> patch_of_piece;      // the patches whose cells the mesh holds, in order
  std::vector<int> first_cell;          // piece k's cells are first_cell[k] .. first_cell[k+1]-1
  std::vector<TensorDiscretization> built;  // per piece: its patch's whole space (cells numbered locally)
  std::vector<std::vector<int>> cells_of_piece;  // per piece: the patch-local cells the mesh holds
};
MultiPatchTensorPart build_multipatch_tensor_part(const MultiPatch& domain, const TensorSpaceOptions& options, int rank,
                                                  int ranks);

// The functions of the tensor space on every patch, numbered from the patches' univariate
// bases alone (no cell built): patch k's function i + n_u j is number[first_function[k] + i +
// n_u j], a shared one numbered where it first occurs, as glue_patches numbers them.
// GeometryError as build_multipatch_tensor when an interface's two sides differ.
struct MultiPatchNumbering {
  std::vector<std::array<BSplineBasis1D, 2>> bases;  // per patch: u, v
  std::vector<int> first_function{0};
  std::vector<int> number;
  int count = 0;
};
MultiPatchNumbering number_multipatch_functions(const MultiPatch& domain, const TensorSpaceOptions& options);

}  // namespace knotwork
