#pragma once
#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "basis/bezier_mesh.hpp"
#include "solver/expression.hpp"
#include "solver/geometry_map.hpp"

namespace knotwork {

// ParaView output. Point data: "solution", and with an exact solution also "exact" and
// "error" (= solution - exact).

// Exact Bezier quadrilaterals (VTK type 77): each cell's geometry control points, its
// rational weights (point data "RationalWeights") and degrees (cell data
// "HigherOrderDegrees"), both set as active attributes so ParaView 5.11 uses them.
// Fields are given as Bezier coefficients that interpolate them at the cell's
// equispaced nodes: exact for the solution whenever it lies in the cell's (rational)
// Bezier space, i.e. for isoparametric spaces; an interpolant otherwise.
void write_bezier_vtu(const std::string& path, const BezierMesh& mesh, const GeometryMap& geometry,
                      const Eigen::VectorXd& coefficients, const ExactSolution* exact);

// The robust fallback: every cell cut into samples x samples linear quads with exact
// values at their corners.
void write_sampled_vtu(const std::string& path, const BezierMesh& mesh, const GeometryMap& geometry,
                       const Eigen::VectorXd& coefficients, const ExactSolution* exact, int samples);

// A ParaView collection (.pvd): (time value, file name relative to the .pvd) per entry.
void write_pvd(const std::string& path, const std::vector<std::pair<double, std::string>>& entries);

}  // namespace knotwork
