#pragma once
// One conforming (C0) space on a multipatch domain from one space per patch, whatever built
// them: the functions of two glued sides are identified by their traces. Each side's cells
// give their Bernstein coefficients along the side; two functions, one per side, with the
// same trace (and weight) become one. The two sides must be cut into the same pieces and every
// trace on one side must be a trace on the other: a space that is not conforming is refused,
// naming the interface, never glued partly.
#include <vector>

#include "basis/core/bezier_mesh.hpp"
#include "basis/core/multipatch.hpp"
#include "basis/core/multivolume.hpp"

namespace knotwork {

struct GluedPatches {
  BezierMesh mesh;  // the patches' cells in patch order; cell.patch is the patch's index
  std::vector<int> first_cell;  // patch k's cells are first_cell[k] .. first_cell[k+1]-1
  std::vector<std::vector<int>> global_function;  // per patch: its function i -> the shared numbering
};

// `patches[k]` is a space on domain.patches[k]: its cells' boxes in that patch's parameter
// domain, cell.boundary[s] >= 0 on the patch's sides, its own interfaces set (or derivable
// from the boxes). All rational or none. The result's boundary ids are exterior_sides(domain),
// named "P:S"; its interfaces are each patch's own and the cell pairs along every interface.
// Throws GeometryError naming the interface (its `where`) when the two sides are cut
// differently, their degrees differ, a trace has no partner, or partners' weights differ.
GluedPatches glue_patches(const MultiPatch& domain, const std::vector<const BezierMesh*>& patches);

// The same for volumes glued face to face (`patches[k]` hexahedra on domain.patches[k], boundary
// ids 0..5 on its faces 1..6): a face's cells are pieces of it, matched as rectangles in the
// frame of the interface's first face, their traces the Bernstein coefficients on the face.
// Boundary ids: exterior_faces(domain), named "P:F"; the interfaces across carry the faces'
// orientation (CellInterface::transposed and reversed ranges).
GluedPatches glue_volumes(const MultiVolume& domain, const std::vector<const BezierMesh*>& patches);

}  // namespace knotwork
