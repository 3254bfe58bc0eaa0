#pragma once
#include <Eigen/Core>
#include <array>
#include <optional>
#include <span>
#include <vector>

#include "basis/core/bezier_mesh.hpp"
#include "basis/core/bspline_basis.hpp"
#include "basis/core/nurbs_patch.hpp"
#include "basis/core/nurbs_volume.hpp"
#include "basis/core/mesh_part.hpp"

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
  int elements_u = 0, elements_v = 0;  // of the whole space, also in a part
  // A rank's part (RowShare with ranks > 1): the mesh holds the element rows from first_row
  // on (the halo rows, then the rank's own), cell c being element (c % elements_u,
  // first_row + c / elements_u); its functions are numbered from part->function_offset and
  // geometry_homogeneous holds the geometry net's rows from net_first_row on.
  int first_row = 0, net_first_row = 0;
  std::optional<MeshPart> part;
};

// Rank `rank` of `ranks`: rank r owns the element rows [n_v r / R, n_v (r + 1) / R) and the
// functions whose support starts in them (function rows are numbered i + n_u j: a contiguous
// block); its part also holds the rows below its own where those functions live.
struct RowShare {
  int rank = 0, ranks = 1;
};

// The cells of a tensor-product space on the grid of its univariate bases' elements, in 2 or 3
// directions (bases u, v[, w]): the slabs [slab_from, slab_to) of elements along the last
// direction, element (i, j[, k]) as cell i + n_u (j [+ n_v k]) from the first slab, functions
// numbered i + n_u j [+ n_u n_v k] less `offset`, extractions pooled per distinct tuple of
// univariate ones. Boundary ids: in 2D bottom 0, right 1, top 2, left 3; in 3D the sides u = 0,
// u = 1, v = 0, v = 1, w = 0, w = 1 are 0..5 (named "1".."6", as G+Smo and GeoPDEs number them).
void add_tensor_cells(BezierMesh& mesh, std::span<const BSplineBasis1D> bases, int slab_from, int slab_to,
                      int offset = 0);

// k-refinement of the patch: every original span cut into equal parts, plus any extra
// knots; new knots get
// continuity C^r, original knots keep min(their continuity, r); degree raised to p.
// Throws std::invalid_argument for impossible requests (p below the geometry degree
// with rational = true, continuity outside [0, p-1]).
// With a RowShare of several ranks, only that rank's part (the element rows it owns and its
// halo): memory per rank ~ 1 / ranks of the whole. Throws std::invalid_argument when there are
// fewer element rows than ranks.
TensorDiscretization build_tensor_discretization(const NurbsPatch& patch, const TensorSpaceOptions& options,
                                                 RowShare share = {});

// The patch's homogeneous control net (w x, w y, w) refined onto geometry_u x geometry_v (bases
// whose knots contain the patch's), net rows first_row .. first_row + rows - 1 along v (rows < 0:
// to the last), numbered i + n_u j from first_row. A part's net is some rows of it; a process
// that needs the whole patch's (a preconditioner applied whole on every process) asks for all.
Eigen::MatrixX3d refined_homogeneous_net(const NurbsPatch& patch, const BSplineBasis1D& geometry_u,
                                         const BSplineBasis1D& geometry_v, int first_row = 0, int rows = -1);

// The analysis space's univariate bases alone (what build_tensor_discretization refines the
// patch into, without building any cell): cheap, for counting and numbering functions.
std::array<BSplineBasis1D, 2> tensor_space_bases(const NurbsPatch& patch, const TensorSpaceOptions& options);

// A trivariate tensor-product space on a NURBS volume (docs/VOLUMES.md): per direction u, v, w
// the degree, the equal elements each knot span of the volume is cut into, and C^r at the new
// knots (-1: p - 1; the volume's knots keep min(their continuity, r)), as for a patch.
// rational: the isoparametric NURBS space (degree >= the volume's in every direction).
struct TensorVolumeOptions {
  std::array<int, 3> degree{2, 2, 2};
  std::array<int, 3> elements_per_span{1, 1, 1};
  std::array<int, 3> continuity{-1, -1, -1};
  bool rational = true;
  std::array<std::vector<double>, 3> extra_knots;  // per direction, inserted with continuity r (as on a patch)
};

struct TensorVolumeDiscretization {
  BezierMesh mesh;                        // hexahedra, functions i + n_u j + n_u n_v k
  std::array<BSplineBasis1D, 3> space;    // the univariate bases (of the whole space, also in a part)
  NurbsVolume volume;                     // the geometry as given, which the map evaluates
  // A rank's part (a RowShare of several ranks): the mesh holds the slabs of elements along w
  // that carry the rank's functions, numbered from part->function_offset; the rank owns the
  // functions that start on its own slabs (as rows along v on a patch).
  std::optional<MeshPart> part;
};

// The space's cells, and with `rational` its weights: the volume's refined onto the space's
// knots (all equal for a polynomial volume: then it is the B-spline space). Throws
// std::invalid_argument for impossible requests, naming the direction, and when there are fewer
// slabs of elements along w than ranks sharing them.
TensorVolumeDiscretization build_tensor_volume(const NurbsVolume& volume, const TensorVolumeOptions& options,
                                               RowShare share = {});

}  // namespace knotwork
