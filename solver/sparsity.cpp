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

LowerPattern lower_pattern(const BezierMesh& mesh, const DofLayout& layout) {
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
  LowerPattern pattern;
  pattern.outer.assign(n + 1, 0);
  auto column = [&](int j, std::vector<int>& rows) {
    rows.clear();
    const int f = layout.function_of_dof[j];
    for (int k = start[f]; k < start[f + 1]; ++k)
      for (int g : mesh.functions(cells[k])) {
        const int d = layout.dof[g];
        if (d >= j) rows.push_back(d);
      }
    std::sort(rows.begin(), rows.end());
    rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
  };
#pragma omp parallel
  {
    std::vector<int> rows;
#pragma omp for schedule(static)
    for (int j = 0; j < n; ++j) {
      column(j, rows);
      pattern.outer[j + 1] = static_cast<int>(rows.size());
    }
  }
  for (int j = 0; j < n; ++j) pattern.outer[j + 1] += pattern.outer[j];
  pattern.inner.resize(pattern.outer[n]);
#pragma omp parallel
  {
    std::vector<int> rows;
#pragma omp for schedule(static)
    for (int j = 0; j < n; ++j) {
      column(j, rows);
      std::copy(rows.begin(), rows.end(), pattern.inner.begin() + pattern.outer[j]);
    }
  }
  return pattern;
}

Eigen::SparseMatrix<double> to_matrix(LowerPattern&& pattern) {
  const int n = pattern.size();
  Eigen::SparseMatrix<double> A(n, n);
  A.resizeNonZeros(pattern.nonzeros());
  std::copy(pattern.outer.begin(), pattern.outer.end(), A.outerIndexPtr());
  std::copy(pattern.inner.begin(), pattern.inner.end(), A.innerIndexPtr());
  std::fill(A.valuePtr(), A.valuePtr() + pattern.nonzeros(), 0.0);
  pattern = LowerPattern{};
  return A;
}

}  // namespace knotwork
