#pragma once
// The tensor family on a domain of several patches ([geometry] file with interfaces).
#include <memory>

#include "basis/tensor/tensor_patch.hpp"
#include "cases/spline_space.hpp"

namespace knotwork {

std::unique_ptr<SplineSpace> make_multipatch_tensor_space(const CaseDescription& c, const TensorSpaceOptions& options);
// Rank `rank` of `ranks`' part of it (under mpirun with method = "petsc"): whole patches per
// rank and the halo cells its functions need; needs at least as many patches as ranks.
std::unique_ptr<SplineSpace> make_multipatch_tensor_part(const CaseDescription& c, const TensorSpaceOptions& options,
                                                         int rank, int ranks);

// The cells and functions of the tensor space on every patch of the case's domain, summed
// (what its memory check needs).
void multipatch_tensor_size(const CaseDescription& c, const TensorSpaceOptions& options, double& cells, double& functions);

}  // namespace knotwork
