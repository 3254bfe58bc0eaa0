#pragma once
#include <Eigen/Core>
#include <functional>
#include <vector>

#include "basis/core/nurbs_patch.hpp"
#include "basis/tmesh/rectangular_partition.hpp"

namespace knotwork {

// The knots of a partition (lines, rays, segments) as polylines in physical space through
// the patch (curved geometries stay curved: `samples` points per edge), with their kind
// (0 line, 1 ray, 2 segment) and the multiplicity `multiplicity_of` gives each.
struct KnotPolylines {
  std::vector<Eigen::MatrixX2d> lines;
  std::vector<int> kind, multiplicity;
};
KnotPolylines knot_polylines(const RectangularPartition& partition, const NurbsPatch& geometry,
                             const std::function<int(bool vertical, double at, double from, double to)>& multiplicity_of,
                             int samples = 8);

}  // namespace knotwork
