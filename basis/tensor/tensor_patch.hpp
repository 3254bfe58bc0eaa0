#pragma once
#include <Eigen/Core>
#include <array>
#include <vector>

#include "basis/core/bezier_mesh.hpp"
#include "basis/core/bspline_basis.hpp"
#include "basis/core/nurbs_patch.hpp"

namespace knotwork {

struct TensorSpaceOptions {
  std::array<int, 2> degree{2, 2};
  std::array<int, 2> elements_per_span{1, 1};  // uniform subdivision of every geometry span
  std::array<int, 2> continuity{-1, -1};       // C^r at new knots; -1 means p-1
  bool rational = true;                        // isoparametric NURBS space
  // Non-uniform h-refinement: further knots (parameter values inside the geometry's
  // domain) per direction, each with continuity C^r like the uniform ones.
  std::array<std::vector<double>, 2> extra_knots;
};

// The analysis space and the geometry, both refined onto the same cells.
struct TensorDiscretization {
  BezierMesh mesh;
  BSplineBasis1D space_u, space_v;
  // Geometry as a spline over the same elements (degree max(p, geometry degree)), in
  // homogeneous form (w*x, w*y, w), control net numbered i + n_u*j.
  BSplineBasis1D geometry_u, geometry_v;
  Eigen::MatrixX3d geometry_homogeneous;
  NurbsPatch patch;  // the geometry as given, which the map evaluates at quadrature points
  int elements_u = 0, elements_v = 0;
};

// k-refinement of the patch: every original span cut into equal parts, plus any extra
// knots; new knots get
// continuity C^r, original knots keep min(their continuity, r); degree raised to p.
// Throws std::invalid_argument for impossible requests (p below the geometry degree
// with rational = true, continuity outside [0, p-1]).
TensorDiscretization build_tensor_discretization(const NurbsPatch& patch,
                                                 const TensorSpaceOptions& options);

}  // namespace knotwork
