#pragma once
#include <Eigen/SparseCore>
#include <vector>

#include "basis/bezier_mesh.hpp"

namespace knotwork {

// Which functions are unknowns: dof[f] in [0, num_free) or -1 (fixed by Dirichlet data).
struct DofLayout {
  std::vector<int> dof;
  std::vector<int> function_of_dof;
  int num_free() const { return static_cast<int>(function_of_dof.size()); }
};
DofLayout make_dof_layout(int num_functions, const std::vector<bool>& fixed);

// Lower triangle (row >= column) of the coupling pattern of the free dofs, in
// compressed-column form with sorted row indices: the layout CHOLMOD reads.
struct LowerPattern {
  std::vector<int> outer;  // size n+1
  std::vector<int> inner;
  int size() const { return static_cast<int>(outer.size()) - 1; }
  long nonzeros() const { return static_cast<long>(inner.size()); }
};
LowerPattern lower_pattern(const BezierMesh& mesh, const DofLayout& layout);
// A compressed column-major matrix with that pattern and zero values (pattern is consumed).
Eigen::SparseMatrix<double> to_matrix(LowerPattern&& pattern);

}  // namespace knotwork
