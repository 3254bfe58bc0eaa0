#include "solver/sparsity.hpp"

#include <algorithm>

namespace knotwork {

DofLayout make_dof_layout(int n, const std::vector<bool>& fixed) {
  DofLayout l;
  l.dof.assign(n, -1);
  for (int f = 0; f < n; ++f)
    if (!fixed[f]) {
      l.dof[f] = static_cast<int>(l.function_of_dof.size());
      l.function_of_dof.push_back(f);
    }
  return l;
}

Eigen::SparseMatrix<double> lower_pattern_matrix(const BezierMesh& mesh, const DofLayout& layout) {
  // Cells of every function (compressed), then for each column the sorted set of
  // coupled dofs below the diagonal. Two passes (count, fill) avoid a vector per column.
  const int nf = mesh.num_functions(), nc = mesh.num_cells();
  std::vector<int> start(nf + 1, 0);
  for (int c = 0; c < nc; ++c)
    for (int f : mesh.functions(c)) ++start[f + 1];
  for (int f = 0; f < nf; ++f) start[f + 1] += start[f];
  std::vector<int> cells(start[nf]);
  {
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (int c = 0; c < nc; ++c)
      for (int f : mesh.functions(c)) cells[fill[f]++] = c;
  }
  const int n = layout.num_free();
  Eigen::SparseMatrix<double> A(n, n);
  int* outer = A.outerIndexPtr();
  outer[0] = 0;
  // A function meets each neighbour once per shared cell ((p+1)^2 times in the interior of a
  // tensor mesh): a per-thread stamp (the column last seen) keeps each row once, so only the
  // distinct rows are sorted.
  auto column = [&](int j, std::vector<int>& rows, std::vector<int>& seen) {
    rows.clear();
    const int f = layout.function_of_dof[j];
    for (int k = start[f]; k < start[f + 1]; ++k)
      for (int g : mesh.functions(cells[k])) {
        const int d = layout.dof[g];
        if (d >= j && seen[d] != j) {
          seen[d] = j;
          rows.push_back(d);
        }
      }
    std::sort(rows.begin(), rows.end());
  };
#pragma omp parallel
  {
    std::vector<int> rows, seen(n, -1);
#pragma omp for schedule(static)
    for (int j = 0; j < n; ++j) {
      column(j, rows, seen);
      outer[j + 1] = static_cast<int>(rows.size());
    }
  }
  for (int j = 0; j < n; ++j) outer[j + 1] += outer[j];
  A.resizeNonZeros(outer[n]);
  int* inner = A.innerIndexPtr();
  double* values = A.valuePtr();
#pragma omp parallel
  {
    std::vector<int> rows, seen(n, -1);
#pragma omp for schedule(static)
    for (int j = 0; j < n; ++j) {
      column(j, rows, seen);
      std::copy(rows.begin(), rows.end(), inner + outer[j]);
      std::fill(values + outer[j], values + outer[j + 1], 0.0);
    }
  }
  return A;
}

}  // namespace knotwork
