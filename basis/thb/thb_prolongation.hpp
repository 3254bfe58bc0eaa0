#pragma once
// The prolongation between two THB spaces of one hierarchy, the second made from the first by
// ThbHierarchy::refine: what a multigrid over adaptive steps needs (studies/adaptive.cpp).
// Computed locally, by the THB basis's preservation of coefficients (Giannelli, Jüttler,
// Speleers 2014): on a leaf of level l, the active functions of level l are the level's
// B-splines untruncated and the coarser functions are combinations of the level's other
// B-splines, so the coefficient of a function of level l in any s of the space is the
// coefficient of s in the level's (locally independent) B-splines on one such leaf.
#include <Eigen/SparseCore>
#include <vector>

#include "basis/thb/thb_hierarchy.hpp"

namespace knotwork {

// P with coarse function j = sum_i P(i, j) fine function i: rows the fine space's functions,
// columns the coarse space's. The fine mesh, leaves and functions per level are what
// ThbHierarchy::build gave for `hierarchy`, which refined the hierarchy the coarse mesh and
// leaves were built from. Entries below 1e-13 are rounding of exact zeros and dropped (the
// true ones lie in [0, 1]). std::logic_error when the two are not nested so (a fine leaf in
// no coarse leaf).
Eigen::SparseMatrix<double> thb_prolongation(const ThbHierarchy& hierarchy, const BezierMesh& coarse_mesh,
                                             const std::vector<ThbCell>& coarse_leaves, const BezierMesh& fine_mesh,
                                             const std::vector<ThbCell>& fine_leaves,
                                             const std::vector<int>& fine_functions_per_level);

}  // namespace knotwork
