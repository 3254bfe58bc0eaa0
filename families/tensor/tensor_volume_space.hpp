#pragma once
// The tensor family on a volume ([geometry] type = "box" or "thick_quarter_annulus"):
// trivariate B-splines or NURBS on hexahedra (docs/VOLUMES.md).
#include <array>
#include <memory>
#include <string>

#include "basis/tensor/tensor_patch.hpp"
#include "cases/spline_space.hpp"

namespace knotwork {

// The names [solver] preconditioner gives the tensor family's fast diagonalization and
// geometric multigrid, on patches and on volumes.
inline const std::string kFastDiagonalization = "fast_diagonalization";
inline const std::string kMultigrid = "multigrid";

// Throws InputError naming [space] when the space cannot be built or would not fit in memory.
// With a RowShare of several ranks, that rank's part: the slabs of hexahedra along w it owns
// and those below where its functions live (SplineSpace::part()).
std::unique_ptr<SplineSpace> make_tensor_volume_space(const CaseDescription& c, const TensorVolumeOptions& options,
                                                     RowShare share = {});

// Refuses, before anything is allocated, a volume space and solve that would not fit in memory.
void check_tensor_volume_memory(const CaseDescription& c, const TensorVolumeOptions& options);

// The memory of a solve on `cells` hexahedra and `functions` unknowns of a space without a
// structured preconditioner (glued volumes, THB): CG with --solver iterative ("auto": BoomerAMG),
// else the direct solve with the case's ordering ("auto": METIS). `method` names the path taken.
double volume_solve_bytes(const CaseDescription& c, double cells, double functions, const std::array<int, 3>& degree,
                          std::string* method = nullptr);

}  // namespace knotwork
