#pragma once
// A multipatch domain of bilinear patches as the quad mesh the G1 family builds on: each knot
// span of a patch of degree 1 x 1 with equal weights is one quad (its control points are the
// grid's vertices), and the vertices of glued sides are one. Curved patches are refused: the
// G1 construction here is the one of bilinear quad meshes (Blidia, Mourrain, Villamizar).
#include <string>

#include "basis/core/multipatch.hpp"
#include "basis/g1/quad_mesh.hpp"

namespace knotwork {

// Throws GeometryError naming the patch (its `where`) that is not bilinear, or the interface
// whose two sides have different numbers of vertices; std::invalid_argument from
// QuadMesh::from_faces (source: `source`) for a mesh it refuses.
QuadMesh quad_mesh_of_bilinear_patches(const MultiPatch& domain, const std::string& source);

}  // namespace knotwork
