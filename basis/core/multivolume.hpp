#pragma once
// A domain made of several NURBS volumes glued face to face: the volumes, the interfaces where
// two faces coincide (with how their parameters match), and named groups of boundary faces.
// Faces are numbered as G+Smo and GeoPDEs number them: 1 u = 0, 2 u = 1, 3 v = 0, 4 v = 1,
// 5 w = 0, 6 w = 1. A face's two coordinates (s, t) are its volume's parameters other than the
// normal one, in the order u, v, w, each mapped onto [0, 1].
#include <array>
#include <string>
#include <vector>

#include "basis/core/bezier_mesh.hpp"
#include "basis/core/multipatch.hpp"
#include "basis/core/nurbs_volume.hpp"

namespace knotwork {

// Face a of one volume is face b of another. As GeoPDEs states it: `same_order` when a's first
// coordinate corresponds to b's first (else to b's second), and `reverse_first` / `reverse_second`
// when a's first / second coordinate runs against its counterpart on b.
struct VolumeInterface {
  PatchSideRef a, b;  // side: the face, 1..6
  bool same_order = true, reverse_first = false, reverse_second = false;
  std::string where;
  // The point of face b at face a's point (s, t).
  std::array<double, 2> on_b(double s, double t) const;
};

struct MultiVolume {
  std::vector<NurbsVolume> patches;
  std::vector<std::string> patch_labels;  // the file's names, in "P:F" boundary names
  std::vector<std::string> patch_where;
  std::vector<VolumeInterface> interfaces;
  std::vector<NamedBoundary> boundaries;  // the file's labels of faces (may be none)
  int num_patches() const { return static_cast<int>(patches.size()); }
};

// Face f (1..6) as the side of a hexahedron.
CellSide cell_side_of_face(int face);
// The volume's parameters (u, v, w) at the point (s, t) of face f.
std::array<double, 3> face_parameters(const NurbsVolume& volume, int face, double s, double t);

// How face a of one volume meets face b of another, found from the geometry: the orientation
// under which their corners coincide (to `tolerance`) and then their points at a 5 x 5 grid
// agree. Returns false when the faces are not one surface.
bool match_faces(const MultiVolume& domain, PatchSideRef a, PatchSideRef b, double tolerance, VolumeInterface& out);

// Every pair of faces that are one surface (interfaces found from the geometry), a before b.
std::vector<VolumeInterface> find_face_interfaces(const MultiVolume& domain);

// The faces that are not interfaces, patch by patch and face by face: the boundary ids of a
// mesh built on the domain, in that order; their names "P:F".
std::vector<PatchSideRef> exterior_faces(const MultiVolume& domain);
std::vector<std::string> exterior_face_names(const MultiVolume& domain, const std::vector<PatchSideRef>& exterior);

// Checks the domain and throws GeometryError naming where the fault was read: every volume
// valid; a declared interface joins two different faces that are one surface under the
// declared orientation (to 1e-9 of the domain's size); no face in two interfaces; every face
// that coincides with another is an interface (a missing one would leave the space
// discontinuous there); a named boundary lists faces that are not interfaces.
void check_multivolume(const MultiVolume& domain);

// The size of the domain's bounding box (for tolerances).
double domain_size(const MultiVolume& domain);

}  // namespace knotwork
