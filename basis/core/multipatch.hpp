#pragma once
// A domain made of several NURBS patches: the patches, the interfaces where two of them meet
// (with the orientation of the shared side), and named groups of boundary sides. The sides of
// a patch are numbered as G+Smo and GeoPDEs number them: 1 is u = 0, 2 is u = 1, 3 is v = 0,
// 4 is v = 1.
#include <array>
#include <string>
#include <vector>

#include "basis/core/bezier_mesh.hpp"
#include "basis/core/nurbs_patch.hpp"

namespace knotwork {

// Side s (1..4) of a patch as the side of its cells (bottom, right, top, left).
CellSide cell_side_of_patch_side(int side);
// The side of the parameter domain a cell side lies on, in the files' numbering.
int patch_side_of_cell_side(CellSide side);

struct PatchSideRef {
  int patch = 0;  // index into MultiPatch::patches
  int side = 1;   // 1..4
  bool operator==(const PatchSideRef&) const = default;
};

// Side a of one patch is side b of another. Along a side the parameter runs from the side's
// first corner to its last (u increasing on sides 3 and 4, v increasing on sides 1 and 2);
// `reversed` says that the two run opposite ways.
struct PatchInterface {
  PatchSideRef a, b;
  bool reversed = false;
  std::string where;  // where it was read ("geometry.txt: line 40"), for messages
};

struct NamedBoundary {
  std::string name;
  std::vector<PatchSideRef> sides;
  std::string where;
};

struct MultiPatch {
  std::vector<NurbsPatch> patches;
  std::vector<std::string> patch_labels;  // the file's name of each patch, in "P:S" boundary names
  std::vector<std::string> patch_where;   // where each patch was read, for messages
  std::vector<PatchInterface> interfaces;
  std::vector<NamedBoundary> boundaries;  // the file's boundary labels (may be none)
  int num_patches() const { return static_cast<int>(patches.size()); }
};

// The sides that are not interfaces, patch by patch and side by side (1..4): the boundary ids
// of a mesh built on the domain, in that order.
std::vector<PatchSideRef> exterior_sides(const MultiPatch& domain);
// Per CellSide, the boundary id (index into `exterior`) of patch p's side there; -1 where the
// side is an interface.
std::array<int, 4> boundary_ids_of_patch(const std::vector<PatchSideRef>& exterior, int p);

// Their names, side_name of each, in that order (a mesh's boundary names).
std::vector<std::string> exterior_side_names(const MultiPatch& domain, const std::vector<PatchSideRef>& exterior);
// Patch p's cell as a cell of the domain's mesh: its patch set, its boundary sides renumbered
// (`boundary_id`: boundary_ids_of_patch).
BezierCell domain_cell(BezierCell cell, int p, const std::array<int, 4>& boundary_id);

// The indices i + nu j of an nu x nv grid (of functions, of control points) along side 1..4,
// in the side's direction (u increasing on sides 3 and 4, v on 1 and 2).
std::vector<int> side_indices(int nu, int nv, int side);

// The file's label of patch p (its 1-based number when the domain has no labels), and "P:S"
// with it for side S.
std::string patch_label(const MultiPatch& domain, int p);
std::string side_name(const MultiPatch& domain, PatchSideRef side);

// `points` equally spaced points (in the parameter) along a side, in the side's direction.
Eigen::MatrixX2d side_curve(const MultiPatch& domain, PatchSideRef side, int points);

// Checks the domain and throws GeometryError naming where the fault was read:
// - every patch is valid (NurbsPatch::validate) and positively oriented (det J > 0 at the
//   Gauss points of each of its knot spans: an inverted or folded patch is refused);
// - no two patches overlap (points inside each patch, 16 per knot span, are not inside another);
// - an interface joins two different existing sides, and no side is in two interfaces;
// - the two sides of an interface are the same curve (to 1e-9 of the domain's size, at points
//   along it), with the same weight function where the patches are rational;
// - a named boundary lists existing sides that are not interfaces, each in one boundary only.
void check_multipatch(const MultiPatch& domain);

}  // namespace knotwork
