// The assembled matrix of a tensor patch whose map is one affine map, from the operator's
// Kronecker form K = d11 K_u (x) M_v + d22 M_u (x) K_v + d12 (C_u (x) C_v^T + C_u^T (x) C_v)
// + c M_u (x) M_v: each entry is four products of univariate band entries, written in place in
// CHOLMOD's layout, where the element loop (solver/assemble_poisson.cpp) evaluates every
// function at every point of every cell and scatters (p + 1)^4 products per cell. Gauss rules
// of p + 1 points integrate both exactly, so the two give the same matrix up to rounding
// (tests/test_tensor_operator.cpp). Also any row's entries (row_entries): a process's owned rows
// of the distributed matrix, from the operator of its part of the patch (solver/poisson_solver.cpp).
// Written here: no library assembles spline matrices.
#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <vector>

#include "solver/sparsity.hpp"
#include "solver/tensor_operator.hpp"

namespace knotwork {

Eigen::SparseMatrix<double> MatrixFreePoisson::lower_matrix(const DofLayout&) const {
  throw std::logic_error("MatrixFreePoisson::lower_matrix: this operator does not assemble its matrix");
}

void MatrixFreePoisson::row_entries(int, int, const int*, double*) const {
  throw std::logic_error("MatrixFreePoisson::row_entries: this operator does not assemble its matrix");
}

Eigen::SparseMatrix<double> MatrixFreePoisson::lower_pattern(const DofLayout&) const {
  throw std::logic_error("MatrixFreePoisson::lower_pattern: this operator does not give its pattern");
}

void MatrixFreePoisson::coupled_functions(int, std::vector<int>&) const {
  throw std::logic_error("MatrixFreePoisson::coupled_functions: this operator does not give its pattern");
}

TensorPoissonOperator::Reach TensorPoissonOperator::reach(const Direction& d, int functions) {
  Reach r;
  r.low.assign(functions, functions);
  r.high.assign(functions, -1);
  for (int f : d.first)  // elements in order, their first function non-decreasing
    for (int a = f; a <= f + d.degree; ++a) {
      r.low[a] = std::min(r.low[a], f);
      r.high[a] = std::max(r.high[a], f + d.degree);
    }
  return r;
}

void TensorPoissonOperator::coupled_functions(int function, std::vector<int>& out) const {
  const int i0 = function % n_u_, j0 = function / n_u_;
  for (int j = reach_v_.low[j0]; j <= reach_v_.high[j0]; ++j)
    for (int i = reach_u_.low[i0]; i <= reach_u_.high[i0]; ++i) out.push_back(i + n_u_ * j);
}

Eigen::SparseMatrix<double> TensorPoissonOperator::lower_matrix(const DofLayout& layout) const {
  if (!assembles_lower())
    throw std::logic_error("TensorPoissonOperator::lower_matrix: an operator made without a geometry net");
  return kronecker_writes() ? write_lower(layout, true) : sum_factorized_lower(layout);
}

TensorPoissonOperator::KroneckerEntries TensorPoissonOperator::kronecker_entries() const {
  const std::array<double, 4>& f = uniform_factors_;
  KroneckerEntries e;
  e.d11 = stiffness_ * f[0], e.d12 = stiffness_ * f[1], e.d22 = stiffness_ * f[2], e.r = reaction_ * f[3];
  e.pu = u_.degree, e.pv = v_.degree;
  e.ku = band_u_.K.data(), e.mu = band_u_.M.data(), e.cu = band_u_.C.data();
  e.kv = band_v_.K.data(), e.mv = band_v_.M.data(), e.cv = band_v_.C.data();
  return e;
}

void TensorPoissonOperator::row_entries(int row, int count, const int* columns, double* values) const {
  if (!writes_rows())
    throw std::logic_error("TensorPoissonOperator::row_entries: the map is not one affine map, or the space is rational");
  const KroneckerEntries entry = kronecker_entries();
  const int i = row % n_u_, j = row / n_u_;
  // A row's columns come in ascending order: one division per row of functions they cross,
  // not two per entry (which cost as much as the entries).
  int j0 = 0, start = 0, end = 0;
  for (int k = 0; k < count; ++k) {
    const int c = columns[k];
    if (c < start || c >= end) j0 = c / n_u_, start = j0 * n_u_, end = start + n_u_;
    const int i0 = c - start;
    values[k] = std::abs(i - i0) <= entry.pu && std::abs(j - j0) <= entry.pv ? entry(i, j, i0, j0) : 0.0;
  }
}

Eigen::SparseMatrix<double> TensorPoissonOperator::lower_pattern(const DofLayout& layout) const {
  return write_lower(layout, false);
}

Eigen::SparseMatrix<double> TensorPoissonOperator::write_lower(const DofLayout& layout, bool with_values) const {
  if (static_cast<long>(layout.dof.size()) != long(n_u_) * n_v_)
    throw std::logic_error("TensorPoissonOperator::write_lower: a layout of another space");
  const Reach &ru = reach_u_, &rv = reach_v_;
  const int n = layout.num_free();
  Eigen::SparseMatrix<double> K(n, n);
  int* outer = K.outerIndexPtr();
  outer[0] = 0;
  // Column d is function (i0, j0); its rows are the free functions (i, j) at or after it that
  // share an element with it, in function order (= dof order): j from j0, i over i0's reach
  // (from i0 on the column's own row of functions).
  const auto for_rows = [&](int d, auto row) {
    const int g = layout.function_of_dof[d], i0 = g % n_u_, j0 = g / n_u_;
    for (int j = j0; j <= rv.high[j0]; ++j)
      for (int i = j == j0 ? i0 : ru.low[i0]; i <= ru.high[i0]; ++i) {
        const int dof = layout.dof[i + n_u_ * j];
        if (dof >= 0) row(dof, i0, j0, i, j);
      }
  };
#pragma omp parallel for schedule(static)
  for (int d = 0; d < n; ++d) {
    int count = 0;
    for_rows(d, [&](int, int, int, int, int) { ++count; });
    outer[d + 1] = count;
  }
  for (int d = 0; d < n; ++d) outer[d + 1] += outer[d];
  K.resizeNonZeros(outer[n]);
  int* inner = K.innerIndexPtr();
  double* values = K.valuePtr();
  const KroneckerEntries entry = kronecker_entries();
#pragma omp parallel for schedule(static)
  for (int d = 0; d < n; ++d) {
    long at = outer[d];
    if (!with_values) {
      for_rows(d, [&](int dof, int, int, int, int) {
        inner[at] = dof;
        values[at] = 0.0;
        ++at;
      });
      continue;
    }
    for_rows(d, [&](int dof, int i0, int j0, int i, int j) {
      inner[at] = dof;
      values[at] = entry(i, j, i0, j0);
      ++at;
    });
  }
  return K;
}

}  // namespace knotwork
