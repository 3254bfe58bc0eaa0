#pragma once
#include <array>
#include "basis/core/nurbs_patch.hpp"
#include "basis/core/nurbs_volume.hpp"

namespace knotwork {

// The built-in single-patch geometries. Each is positively oriented (det J > 0), and its
// parameter sides are bottom (v=0), right (u=1), top (v=1), left (u=0).

// [x0,x1] x [y0,y1], bilinear; u along x, v along y.
NurbsPatch rectangle_patch(double x0, double y0, double x1, double y1);

// { r_in <= r <= r_out, x >= 0, y >= 0 } as an exact NURBS: u radial (degree 1, from r_in
// to r_out), v angular (degree 2, weights 1, 1/sqrt(2), 1, from the x- to the y-axis).
NurbsPatch quarter_annulus_patch(double inner_radius, double outer_radius);

// (-1,1)^2 minus [0,1]x[-1,0] as ONE patch folded with a C0 knot at u = 1/2: bottom side
// (v=0) is the re-entrant polyline (0,-1) -> (0,0) -> (1,0); top side (v=1) the outer polyline
// (-1,-1) -> (-1,1) -> (1,1); left side is y = -1, right side is x = 1. Bilinear on the two
// convex quads either side of the diagonal (0,0)-(-1,1). The fold stays C0 under refinement.
NurbsPatch lshape_patch();

// The built-in volumes, positively oriented (det J > 0), sides u = 0, u = 1, v = 0, v = 1,
// w = 0, w = 1 numbered "1".."6".

// [x0,x1] x [y0,y1] x [z0,z1], trilinear; u along x, v along y, w along z.
NurbsVolume box_volume(const Eigen::Vector3d& lower, const Eigen::Vector3d& upper);

// The Fichera corner (-1,1)^3 less the octant [0,1]^3: the box (-1,1)^3, trilinear with a C0
// knot at the middle of each direction (x, y, z = 0 at u, v, w = 1/2), and the octant's part
// of the parameter box, [1/2, 1]^3, to remove from it (CaseDescription::volume_removed_boxes).
NurbsVolume fichera_box_volume();
constexpr std::array<double, 6> kFicheraRemovedBox{0.5, 1, 0.5, 1, 0.5, 1};

// The quarter annulus above extruded along z to [0, height]: u radial (degree 1), v angular
// (degree 2, the exact arc), w along z (degree 1).
NurbsVolume thick_quarter_annulus_volume(double inner_radius, double outer_radius, double height);

}  // namespace knotwork
