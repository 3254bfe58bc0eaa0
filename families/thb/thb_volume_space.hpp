#pragma once
// The THB family on a volume: the octree of basis/thb's hierarchy over the volume's knot spans.
#include <memory>

#include "basis/thb/thb_hierarchy.hpp"
#include "cases/case_reader.hpp"
#include "cases/spline_space.hpp"

namespace knotwork {

// The THB space of a hierarchy on the case's patch or volume (thb_family.cpp): its refine()
// halves marked cells (quadrants or octants) with the hierarchy's grading.
std::unique_ptr<SplineSpace> make_thb_space(const CaseDescription& c, ThbHierarchy hierarchy);

// [space] of a THB volume case (degree, elements, admissibility, quadrature), after [geometry]
// was found to be a volume.
void read_thb_volume_case(const CaseDocument& doc, CaseDescription& c, const std::vector<std::string>& keys);

// The uniform start space of `level` (every knot span of the volume cut into elements << level
// pieces per direction); its refine() halves marked hexahedra into octants.
std::unique_ptr<SplineSpace> make_thb_volume_space(const CaseDescription& c, int level);

// --degree / --elements and --levels on a THB volume case.
void override_thb_volume_space(CaseDescription& c, int degree, int elements);
void check_thb_volume_levels(const CaseDescription& c, int levels);

}  // namespace knotwork
