#pragma once
#include <Eigen/SparseCore>
#include <vector>

#include "basis/core/bezier_mesh.hpp"

namespace knotwork {

// Which functions are unknowns: dof[f] in [0, num_free) or -1 (fixed by Dirichlet data).
struct DofLayout {
  std::vector<int> dof;
  std::vector<int> function_of_dof;
  int num_free() const { return static_cast<int>(function_of_dof.size()); }
};
DofLayout make_dof_layout(int num_functions, const std::vector<bool>& fixed);

// The lower triangle (row >= column) of the coupling pattern of the free dofs, as a
// compressed column-major matrix with sorted row indices and zero values: the layout
// CHOLMOD reads. Built in place, in two threaded passes (count, fill).
Eigen::SparseMatrix<double> lower_pattern_matrix(const BezierMesh& mesh, const DofLayout& layout);

}  // namespace knotwork
