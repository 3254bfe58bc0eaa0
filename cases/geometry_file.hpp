#pragma once
// The domains read from the field's own files: G+Smo's XML (`.xml`) and GeoPDEs' geometry text
// format v2.1 (`.txt`), both read from their public descriptions. Every reader throws
// InputError naming the file, the line and what is wrong; read_geometry_file also checks the
// domain (check_multipatch: orientation, matching interfaces, boundary sides).
#include <string>

#include "basis/core/multipatch.hpp"
#include "basis/core/multivolume.hpp"
#include "basis/core/nurbs_volume.hpp"

namespace knotwork {

MultiPatch read_geometry_file(const std::string& path);

// A volume read from a file: one trivariate patch, the file's label of it, and its named
// boundaries, whose sides are faces 1..6 (u = 0, u = 1, v = 0, v = 1, w = 0, w = 1). A file of
// several volumes fills `domain` (its volumes, interfaces and labels: multivolume.hpp) and
// `volume` with the first.
struct VolumeFile {
  NurbsVolume volume;
  std::string label, where;
  std::vector<NamedBoundary> boundaries;
  MultiVolume domain;
};

// The parametric dimension of the file's domain, 2 or 3: GeoPDEs' ndim, or for G+Smo the
// MultiPatch's parDim, else whether a geometry is a TensorBSpline3/TensorNurbs3. InputError
// as the readers (an unknown extension, a malformed file).
int geometry_file_dimension(const std::string& path);

// The volume of a .xml or .txt file, validated (NurbsVolume::validate); InputError naming the
// file, the line and what is wrong, e.g. a planar patch where a volume is read.
VolumeFile read_volume_file(const std::string& path);
int geopdes_text_dimension(const std::string& path);
VolumeFile read_geopdes_volume(const std::string& path);
int gismo_xml_dimension(const std::string& path);
VolumeFile read_gismo_volume(const std::string& path);

// The whole text of a geometry file; InputError when it is missing, a directory, unreadable
// or larger than 256 MB (both readers hold it in memory).
std::string read_geometry_text(const std::string& path);

// GeoPDEs: patches numbered from 1 (their labels "1", "2", ...), control points in homogeneous
// form (w x, w y), a boundary named "BOUNDARY n" labelled "n".
MultiPatch read_geopdes_text(const std::string& path);

// G+Smo: TensorBSpline2 and TensorNurbs2 geometries (Euclidean control points, weights in the
// basis), labelled by their id; a MultiPatch's patches, interfaces and boundaries. Without a
// MultiPatch every geometry of the file is a patch, with no interface.
MultiPatch read_gismo_xml(const std::string& path);

// Writes the domain as G+Smo XML (patch ids 0, 1, ...; named boundaries kept), which
// read_gismo_xml reads back to the same patches, interfaces and boundaries. Written whole or
// not at all (write_file_atomically); InputError when it cannot be written.
void write_gismo_xml(const MultiPatch& domain, const std::string& path);

}  // namespace knotwork
