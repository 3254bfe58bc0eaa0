#pragma once
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "basis/g1/g1_basis.hpp"
#include "basis/g1/g1_refine.hpp"
#include "cases/case_file.hpp"
#include "basis/core/geometry_map.hpp"

namespace knotwork {

// A family "g1" case at one refinement level: the G1 space on the subdivided quad mesh and
// the geometry, which is the G1 spline fitted once on the case's own (coarse) mesh and
// restricted exactly to the finer cells (subdivision keeps it in every finer space).
struct G1Discretization {
  QuadMesh coarse;
  GluingData coarse_gluing;
  G1Refinement level;                 // mesh, gluing and origin of every face
  int levels = 0;                     // subdivisions from the coarse mesh
  G1Basis basis;
  BezierMesh mesh;                    // 4 cells per face, cell 4 f + 2 ht + hs
  // The geometry per cell: Bezier patches in R^2 (planar cases) or R^3 (surfaces).
  std::unique_ptr<BezierCellsGeometryMap> geometry;
  double fit_deviation = 0;           // largest distance fitted - target coefficient (coarse)
  double min_regularity = 0;          // planar: min det J / max det J; surface: min |x_u x x_v| / max
  int worst_face = -1;                // coarse face (0-based) where min_regularity occurs
  // The same at the corners and side midpoints of every cell (never quadrature points;
  // surfaces: |x_u x x_v| relative to the largest there): a
  // value <= 0 means the map is singular on a cell boundary (e.g. at an extraordinary vertex
  // or where C^0 gluing data meet a C^1 split), which the Gauss points do not see but the
  // approximation does. Reported, with the point, not refused.
  double min_regularity_nodes = 0;
  Eigen::Vector3d singular_point = Eigen::Vector3d::Zero();
  double shape_distance = 0;          // sphere/torus: largest distance of a Gauss point from the exact shape
  double boundary_deviation = 0;      // planar: largest distance of a boundary point from its straight edge
};

// The cell interfaces of the BezierMesh of a G1 space on `mesh` (4 cells per face, cell
// 4 f + 2 ht + hs): inside each face, and across every interior edge of the quad mesh with
// the orientation of the two faces' corner frames.
std::vector<CellInterface> g1_cell_interfaces(const QuadMesh& mesh);

// Throws InputError naming the case file and field (bad gluing data, a degree below an
// edge's separability, a fit that is not regular: naming the face).
G1Discretization discretize_g1(const CaseDescription& c, int extra_levels,
                               const std::function<void(const std::string&)>& progress = {});

// The largest jump of the physical (surface) gradient of u_h across interior edges of the
// level's mesh, relative to the largest gradient seen, at `samples` points per cell side.
double g1_gradient_jump(const G1Discretization& d, const Eigen::VectorXd& coefficients, int samples = 7);

}  // namespace knotwork
