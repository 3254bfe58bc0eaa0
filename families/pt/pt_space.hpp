#pragma once
// Family "pt" parts that tests and tools look at (the commands see only SplineSpace).
#include <vector>

#include "basis/pt/pt_spline.hpp"
#include "cases/spline_space.hpp"

namespace knotwork {

// The case's starting T-mesh in parameter coordinates at uniform level `level`: [space]
// cells (inline or from the tmesh file) or else the tensor grid of the geometry's knot spans,
// each cut into [space] elements * 2^level parts, then the segments. Throws InputError.
std::vector<RationalBox> pt_start_cells(const CaseDescription& c, int level = 0);

// The C0 lines and the T-mesh cells (in the order of its BezierMesh's cells) of a family "pt"
// space; null for any other space. The space keeps no exact basis: it is rounded into the
// mesh and dropped.
const C0Lines* pt_c0_lines_of(const SplineSpace& space);
const std::vector<RationalBox>* pt_cells_of(const SplineSpace& space);

}  // namespace knotwork
