// The assembled matrix of a tensor patch on any map (curved, piecewise affine, NURBS spaces),
// by sum factorization over whole columns of elements: no element matrices, no scatter.
// Written here: no library on this machine assembles spline matrices.
//
// K_(i,j),(i0,j0) = sum_{s,t} int D_st T^s_(i,j) T^t_(i0,j0), with T the three product terms
// N_i' N_j, N_i N_j', N_i N_j and D the point coefficients (row_coefficients). For a column
// row j0 the v-sums come first, once for the whole u direction:
//   Y_ab[j](x_q) = sum over the v-points shared by j and j0 of D_st V^sv_j V^tv_j0
// (a, b the u-parts of s, t: derivative or value), then each entry is one sum along u:
//   K = sum over the u-points shared by i and i0 of U^a_i U^b_i0 Y_ab[j].
// Per function that is O(p^4) products in 2D; the element loop's element matrices cost
// O(p^6) per cell, plus their scatter. The rules are the operator's (the assembly's Gauss
// rules), so the two give the same matrix up to rounding (tests/test_tensor_operator.cpp).
#include <omp.h>

#include <algorithm>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "basis/core/input_error.hpp"
#include "solver/assemble_poisson.hpp"
#include "solver/sparsity.hpp"
#include "solver/tensor_operator.hpp"

namespace knotwork {

namespace {

// Per function of one direction, its elements [low, high] (first[e] <= f <= first[e] + p).
void elements_of_functions(const std::vector<int>& first, int degree, int functions, std::vector<int>& low,
                           std::vector<int>& high) {
  low.assign(functions, std::numeric_limits<int>::max());
  high.assign(functions, -1);
  for (int e = 0; e < int(first.size()); ++e)
    for (int a = first[e]; a <= first[e] + degree; ++a) low[a] = std::min(low[a], e), high[a] = std::max(high[a], e);
}

}  // namespace

Eigen::SparseMatrix<double> TensorPoissonOperator::sum_factorized_lower(const DofLayout& layout) const {
  Eigen::SparseMatrix<double> K = write_lower(layout, false);  // the pattern, in place
  const int* outer = K.outerIndexPtr();
  double* values = K.valuePtr();
  const bool rational = weights_.size() > 0;
  const int pu = u_.degree, pv = v_.degree, Pu = pu + 1, Pv = pv + 1, qu = u_.points, qv = v_.points;
  const size_t along = size_t(u_.elements) * qu;
  std::vector<int> low_u, high_u, low_v, high_v;
  elements_of_functions(u_.first, pu, n_u_, low_u, high_u);
  elements_of_functions(v_.first, pv, n_v_, low_v, high_v);
  const Reach &ru = reach_u_, &rv = reach_v_;
  // The lowest cell (eu + E_u ev) where det J <= 0, and det J there.
  long bad_cell = std::numeric_limits<long>::max();
  double bad_det = 0;
#pragma omp parallel
  {
    // The element rows a column row needs (at most p_v + 1, consecutive): slot ev mod (p_v + 1).
    std::vector<RowCoefficients> rows(Pv);
    // Y_ab[j - j0] at every u-point: four arrays (dd, dv, vd, vv) per row j.
    std::vector<double> Y(size_t(Pv) * 4 * along);
    std::vector<double> acc;
    const auto coefficients = [&](int ev) -> const RowCoefficients& {
      RowCoefficients& r = rows[ev % Pv];
      if (r.element_row != ev) {
        row_coefficients(ev, r);
        if (r.bad_element >= 0) {
          const long cell = r.bad_element + long(u_.elements) * ev;
#pragma omp critical(knotwork_sum_factorized_det)
          if (cell < bad_cell) bad_cell = cell, bad_det = r.min_det;
        }
      }
      return r;
    };
#pragma omp for schedule(static)
    for (int j0 = 0; j0 < n_v_; ++j0) {
      const int j_last = rv.high[j0];
      std::fill(Y.begin(), Y.begin() + size_t(j_last - j0 + 1) * 4 * along, 0.0);
      // The v-sums: every element of j0 that j shares, every v-point there, the whole u line.
      for (int ev = low_v[j0]; ev <= high_v[j0]; ++ev) {
        const RowCoefficients& r = coefficients(ev);
        const int fv = v_.first[ev];
        for (int j = j0; j <= std::min(j_last, fv + pv); ++j) {
          double* y = &Y[size_t(j - j0) * 4 * along];
          double *ydd = y, *ydv = y + along, *yvd = y + 2 * along, *yvv = y + 3 * along;
          for (int q = 0; q < qv; ++q) {
            const size_t t = (size_t(ev) * qv + q) * Pv;
            const double vv = v_.value[t + j - fv], vd = v_.derivative[t + j - fv];
            const double vv0 = v_.value[t + j0 - fv], vd0 = v_.derivative[t + j0 - fv];
            const double* d00 = &r.d[0][size_t(q) * along];
            const double* d01 = &r.d[1][size_t(q) * along];
            const double* d11 = &r.d[3][size_t(q) * along];
            const double* d22 = &r.d[5][size_t(q) * along];
            const double c_dd = vv * vv0, c_dv = vv * vd0, c_vd = vd * vv0, c_vv = vd * vd0;
            if (!rational) {
#pragma omp simd
              for (size_t x = 0; x < along; ++x) {
                ydd[x] += d00[x] * c_dd;
                ydv[x] += d01[x] * c_dv;
                yvd[x] += d01[x] * c_vd;
                yvv[x] += d11[x] * c_vv + d22[x] * c_dd;
              }
            } else {
              const double* d02 = &r.d[2][size_t(q) * along];
              const double* d12 = &r.d[4][size_t(q) * along];
              const double c_mixed = vd * vv0 + vv * vd0;
#pragma omp simd
              for (size_t x = 0; x < along; ++x) {
                ydd[x] += d00[x] * c_dd;
                ydv[x] += d01[x] * c_dv + d02[x] * c_dd;
                yvd[x] += d01[x] * c_vd + d02[x] * c_dd;
                yvv[x] += d11[x] * c_vv + d12[x] * c_mixed + d22[x] * c_dd;
              }
            }
          }
        }
      }
      // The u-sums, one column (i0, j0) at a time: its entries over rows j0..j_last and the
      // u reach of i0, added up in acc, then written in the pattern's order.
      for (int i0 = 0; i0 < n_u_; ++i0) {
        const int g0 = i0 + n_u_ * j0, d = layout.dof[g0];
        if (d < 0) continue;
        const int i_low = ru.low[i0], width = ru.high[i0] - i_low + 1;
        acc.assign(size_t(j_last - j0 + 1) * width, 0.0);
        for (int eu = low_u[i0]; eu <= high_u[i0]; ++eu) {
          const int fu = u_.first[eu], a0 = i0 - fu;
          for (int q = 0; q < qu; ++q) {
            const size_t x = size_t(eu) * qu + q, t = x * Pu;
            const double ud0 = u_.derivative[t + a0], uv0 = u_.value[t + a0];
            const double* ud = &u_.derivative[t];
            const double* uv = &u_.value[t];
            for (int j = j0; j <= j_last; ++j) {
              const double* y = &Y[size_t(j - j0) * 4 * along];
              const double cd = ud0 * y[x] + uv0 * y[along + x], cv = ud0 * y[2 * along + x] + uv0 * y[3 * along + x];
              double* a = &acc[size_t(j - j0) * width + (fu - i_low)];
              for (int k = 0; k < Pu; ++k) a[k] += ud[k] * cd + uv[k] * cv;
            }
          }
        }
        // The pattern's order (write_lower): j from j0, i over i0's reach (from i0 on row j0).
        long at = outer[d];
        const double w0 = rational ? weights_[g0] : 1.0;
        for (int j = j0; j <= j_last; ++j)
          for (int i = j == j0 ? i0 : i_low; i <= ru.high[i0]; ++i) {
            const int g = i + n_u_ * j;
            if (layout.dof[g] < 0) continue;
            const double value = acc[size_t(j - j0) * width + (i - i_low)];
            values[at++] = rational ? value * w0 * weights_[g] : value;
          }
      }
    }
  }
  if (bad_cell != std::numeric_limits<long>::max()) {
    const int eu = int(bad_cell % u_.elements), ev = int(bad_cell / u_.elements);
    const std::vector<double> bu = space_u_.breakpoints(), bv = space_v_.breakpoints();
    // det J of the map from the cell's reference square, as the element loop reports it.
    bad_det *= (bu[eu + 1] - bu[eu]) * (bv[ev + 1] - bv[ev]);
    // The element loop's words (solver/assemble_poisson.cpp), whichever path assembled.
    std::ostringstream s;
    s << "geometry has a non-positive Jacobian (det J = " << bad_det << ") at a quadrature point of "
      << describe_cell(int(bad_cell), bu[eu], bu[eu + 1], bv[ev], bv[ev + 1])
      << (bad_det == 0 ? ": the map is degenerate there (a collapsed edge or corner, or a domain too small for double "
                         "precision)"
                       : ": the map folds over or is oriented clockwise");
    throw GeometryError(s.str());
  }
  return K;
}

}  // namespace knotwork
