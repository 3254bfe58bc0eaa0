#pragma once
// The THB family on a domain of several patches ([geometry] file with interfaces).
#include <memory>

#include "basis/tensor/tensor_patch.hpp"
#include "cases/spline_space.hpp"

namespace knotwork {

// The uniform start space of `level` (every patch's knot spans cut into elements << level
// pieces), glued C0 across the interfaces; its refine() keeps it conforming.
std::unique_ptr<SplineSpace> make_thb_multipatch_space(const CaseDescription& c, const TensorSpaceOptions& space,
                                                       int admissibility, int level);

}  // namespace knotwork
