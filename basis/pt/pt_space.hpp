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

// The PT-spline basis and T-mesh of a family "pt" space; null for any other space.
const PtSplineBasis* pt_basis_of(const SplineSpace& space);
const RectangularPartition* pt_tmesh_of(const SplineSpace& space);

}  // namespace knotwork
