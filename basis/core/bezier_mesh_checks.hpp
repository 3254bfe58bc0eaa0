#pragma once
// Checks every spline space gets from `knotwork basis`, whatever its family: partition of
// unity and linear independence of the functions, read off their Bezier coefficients.
#include "basis/core/bezier_mesh.hpp"

namespace knotwork {

// Largest |sum_i R_i - 1| over the cells' Bernstein coefficients: the functions are a
// partition of unity exactly when every column of the (rational-adjusted) extraction sums to 1.
double partition_of_unity_error(const BezierMesh& mesh);

// Numerical rank (dense column-pivoted QR, threshold 1e-10) of all functions' Bezier
// coefficients over all cells; -1 when the matrix would have more than 4e7 entries.
long bezier_rank(const BezierMesh& mesh);

}  // namespace knotwork
