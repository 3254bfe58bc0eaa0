#include "solver/affine_volume_operator.hpp"

#include <omp.h>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "basis/core/input_error.hpp"
#include "quadrature/gauss_legendre.hpp"
#include "solver/fast_diagonalization_3d.hpp"
#include "solver/sparsity.hpp"

namespace knotwork {

namespace {

constexpr int kMaxDegree = 15;

}  // namespace

AffineVolumeOperator::Direction AffineVolumeOperator::direction(const BSplineBasis1D& space, int points, bool matrices) {
  Direction d;
  d.degree = space.degree();
  if (d.degree > kMaxDegree) throw std::invalid_argument("AffineVolumeOperator: degree above 15");
  d.points = points > 0 ? points : d.degree + 1;
  const QuadratureRule1D rule = gauss_legendre(d.points);
  const std::vector<int> spans = space.element_spans();
  const auto& t = space.knots();
  const int p = d.degree, P = p + 1, Q = d.points, n = space.num_functions(), width = 2 * p + 1;
  d.elements = static_cast<int>(spans.size());
  d.first.resize(spans.size());
  d.value.resize(spans.size() * Q * P);
  d.derivative.resize(d.value.size());
  d.node.resize(spans.size() * Q);
  d.weight.resize(d.node.size());
  if (matrices) {
    d.K.assign(size_t(n) * width, 0.0);
    d.M.assign(d.K.size(), 0.0);
    d.D.assign(d.K.size(), 0.0);
  }
  double table[2 * (kMaxDegree + 1)];
  for (int e = 0; e < d.elements; ++e) {
    const int s = spans[e];
    const double a = t[s], h = t[s + 1] - t[s];
    d.first[e] = s - p;
    for (int q = 0; q < Q; ++q) {
      const double x = a + h * rule.nodes[q];
      d.node[e * Q + q] = x;
      d.weight[e * Q + q] = h * rule.weights[q];
      space.evaluate_derivatives(s, x, 1, table);
      for (int b = 0; b < P; ++b) {
        d.value[(size_t(e) * Q + q) * P + b] = table[b];
        d.derivative[(size_t(e) * Q + q) * P + b] = table[P + b];
      }
    }
    if (!matrices) continue;
    // K and M summed for c >= r and mirrored, so that entry(row, column) and entry(column, row)
    // are the same bits (a distributed solve's rows agree with the serial lower triangle).
    for (int r = 0; r < P; ++r)
      for (int c = 0; c < P; ++c) {
        double k = 0, m = 0, mixed = 0;
        const int lo = std::min(r, c), hi = std::max(r, c);
        for (int q = 0; q < Q; ++q) {
          const double* v = &d.value[(size_t(e) * Q + q) * P];
          const double* dv = &d.derivative[(size_t(e) * Q + q) * P];
          const double w = d.weight[e * Q + q];
          k += w * dv[lo] * dv[hi];
          m += w * v[lo] * v[hi];
          mixed += w * dv[r] * v[c];
        }
        const size_t at = size_t(d.first[e] + r) * width + (c - r + p);
        d.K[at] += k;
        d.M[at] += m;
        d.D[at] += mixed;
      }
  }
  d.low.assign(n, n);
  d.high.assign(n, -1);
  for (int f : d.first)  // elements in order: their first functions do not decrease
    for (int a = f; a <= f + p; ++a) d.low[a] = std::min(d.low[a], f), d.high[a] = std::max(d.high[a], f + p);
  return d;
}

AffineVolumeOperator::AffineVolumeOperator(const std::array<BSplineBasis1D, 3>& space, const AffineVolumeMap& map,
                                           double stiffness, double reaction, std::array<int, 3> points, int error_points_w)
    : space_(space), stiffness_(stiffness), reaction_(reaction), points_(points), error_points_w_(error_points_w), map_(map) {
  det_ = map.jacobian.determinant();
  if (!(det_ > 0)) throw std::invalid_argument("AffineVolumeOperator: the map's Jacobian determinant is not positive");
  for (int k = 0; k < 3; ++k) {
    d_[k] = direction(space[k], points[k]);
    n_[k] = space[k].num_functions();
    ends_[k] = space[k].breakpoints();
  }
  const Eigen::Matrix3d G = stiffness * det_ * (map.jacobian.transpose() * map.jacobian).inverse();
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) g_[a][b] = G(a, b);
  r_ = reaction * det_;
}

void AffineVolumeOperator::element_points(const Direction& U, const Direction& V, const Direction& W, int eu, int ev, int ew,
                                          double* x, double* y, double* z) const {
  const int Qu = U.points, Qv = V.points, Qw = W.points;
  for (int c = 0; c < Qw; ++c)
    for (int b = 0; b < Qv; ++b)
      for (int a = 0; a < Qu; ++a) {
        const Eigen::Vector3d p =
            map_.origin + map_.jacobian * Eigen::Vector3d(U.node[eu * Qu + a], V.node[ev * Qv + b], W.node[ew * Qw + c]);
        const int q = a + Qu * (b + Qv * c);
        x[q] = p[0], y[q] = p[1], z[q] = p[2];
      }
}

std::shared_ptr<const AffineVolumeOperator> AffineVolumeOperator::on_spaces(const std::array<BSplineBasis1D, 3>& space) const {
  return std::make_shared<AffineVolumeOperator>(space, map_, stiffness_, reaction_, points_, error_points_w_);
}

namespace {

// y = B x along mode `along` of an array x of dimensions `in` (first index fastest) whose
// entries along that mode are the functions in_first, in_first + 1, ...; y has the same
// dimensions but out_count entries along the mode, the functions out_first, ... (rows of B, a
// band of half-width p: entry (a, c) at a (2p + 1) + c - a + p; B^T with `transposed`).
void band_rows(const std::vector<double>& band, int p, bool transposed, int along, const std::array<int, 3>& in, int in_first,
               int out_first, int out_count, const double* x, double* y) {
  long inner = 1, outer = 1;
  for (int k = 0; k < along; ++k) inner *= in[k];
  for (int k = along + 1; k < 3; ++k) outer *= in[k];
  const int width = 2 * p + 1, m = in[along];
  for (long o = 0; o < outer; ++o) {
    const double* xo = x + o * m * inner;
    double* yo = y + o * out_count * inner;
    for (int a = 0; a < out_count; ++a) {
      const int row = out_first + a;
      double* ya = yo + a * inner;
      std::fill(ya, ya + inner, 0.0);
      for (int c = std::max(0, row - p - in_first); c <= std::min(m - 1, row + p - in_first); ++c) {
        const int column = in_first + c;
        const double b = transposed ? band[size_t(column) * width + (row - column + p)] : band[size_t(row) * width + (column - row + p)];
        const double* xc = xo + c * inner;
        for (long i = 0; i < inner; ++i) ya[i] += b * xc[i];
      }
    }
  }
}

}  // namespace

void AffineVolumeOperator::apply_box(const double* x, const FunctionBox& free, const FunctionBox& rows, double* out) const {
  // The rows' reach within the free box: the columns they couple to.
  FunctionBox reach;
  for (int d = 0; d < 3; ++d) {
    const int p = d_[d].degree;
    reach.first[d] = std::max(free.first[d], rows.first[d] - p);
    reach.count[d] = std::min(free.first[d] + free.count[d], rows.first[d] + rows.count[d] + p) - reach.first[d];
  }
  thread_local std::vector<double> xr, a, b, c;
  xr.resize(reach.size());
  long at = 0;
  for (int k = 0; k < reach.count[2]; ++k)
    for (int j = 0; j < reach.count[1]; ++j) {
      const double* line = x + (reach.first[0] - free.first[0]) +
                           long(free.count[0]) * ((reach.first[1] - free.first[1] + j) + long(free.count[1]) * (reach.first[2] - free.first[2] + k));
      std::copy(line, line + reach.count[0], xr.data() + at);
      at += reach.count[0];
    }
  const Direction &U = d_[0], &V = d_[1], &W = d_[2];
  const std::array<int, 3> r0 = reach.count;
  const std::array<int, 3> r1{rows.count[0], reach.count[1], reach.count[2]}, r2{rows.count[0], rows.count[1], reach.count[2]};
  a.resize(long(r1[0]) * r1[1] * r1[2]);
  b.resize(long(r2[0]) * r2[1] * r2[2]);
  c.resize(rows.size());
  struct Factor {
    const std::vector<double>* band;
    bool transposed;
  };
  // out += coefficient (B_w (x) B_v (x) B_u) x over the rows, the terms of apply().
  const auto add = [&](double coefficient, Factor fu, Factor fv, Factor fw) {
    if (coefficient == 0) return;
    band_rows(*fu.band, U.degree, fu.transposed, 0, r0, reach.first[0], rows.first[0], rows.count[0], xr.data(), a.data());
    band_rows(*fv.band, V.degree, fv.transposed, 1, r1, reach.first[1], rows.first[1], rows.count[1], a.data(), b.data());
    band_rows(*fw.band, W.degree, fw.transposed, 2, r2, reach.first[2], rows.first[2], rows.count[2], b.data(), c.data());
    for (long i = 0; i < rows.size(); ++i) out[i] += coefficient * c[i];
  };
  const Factor Mu{&U.M, false}, Mv{&V.M, false}, Mw{&W.M, false};
  // The diagonal terms share their products (7 band products where one by one took 12):
  // K_u x and M_u x; M_v (K_u x), K_v (M_u x), M_v (M_u x); then
  // M_w (g00 M_v K_u x + g11 K_v M_u x + r M_v M_u x) + g22 K_w (M_v M_u x).
  {
    thread_local std::vector<double> uK, vM, vK;
    uK.resize(a.size());
    vM.resize(b.size());
    vK.resize(b.size());
    band_rows(U.K, U.degree, false, 0, r0, reach.first[0], rows.first[0], rows.count[0], xr.data(), uK.data());
    band_rows(U.M, U.degree, false, 0, r0, reach.first[0], rows.first[0], rows.count[0], xr.data(), a.data());
    band_rows(V.M, V.degree, false, 1, r1, reach.first[1], rows.first[1], rows.count[1], uK.data(), b.data());
    band_rows(V.K, V.degree, false, 1, r1, reach.first[1], rows.first[1], rows.count[1], a.data(), vK.data());
    band_rows(V.M, V.degree, false, 1, r1, reach.first[1], rows.first[1], rows.count[1], a.data(), vM.data());
    const double g00 = g_[0][0], g11 = g_[1][1], r = r_;
    for (size_t i = 0; i < b.size(); ++i) b[i] = g00 * b[i] + g11 * vK[i] + r * vM[i];
    band_rows(W.M, W.degree, false, 2, r2, reach.first[2], rows.first[2], rows.count[2], b.data(), out);
    if (g_[2][2] != 0) {
      band_rows(W.K, W.degree, false, 2, r2, reach.first[2], rows.first[2], rows.count[2], vM.data(), c.data());
      for (long i = 0; i < rows.size(); ++i) out[i] += g_[2][2] * c[i];
    }
  }
  add(g_[0][1], {&U.D, false}, {&V.D, true}, Mw);
  add(g_[0][1], {&U.D, true}, {&V.D, false}, Mw);
  add(g_[0][2], {&U.D, false}, Mv, {&W.D, true});
  add(g_[0][2], {&U.D, true}, Mv, {&W.D, false});
  add(g_[1][2], Mu, {&V.D, false}, {&W.D, true});
  add(g_[1][2], Mu, {&V.D, true}, {&W.D, false});
}

void AffineVolumeOperator::apply_within(const double* x, const FunctionBox& free, double* out) const {
  // Slabs of 16 layers along w (their reach adds 2p layers: a quarter more work at p = 2).
  constexpr int kSlab = 16;
  const int slabs = (free.count[2] + kSlab - 1) / kSlab;
  const long layer = long(free.count[0]) * free.count[1];
#pragma omp parallel for schedule(dynamic)
  for (int s = 0; s < slabs; ++s) {
    FunctionBox rows = free;
    rows.first[2] = free.first[2] + s * kSlab;
    rows.count[2] = std::min(kSlab, free.count[2] - s * kSlab);
    apply_box(x, free, rows, out + layer * s * kSlab);
  }
}

int AffineVolumeOperator::max_row_nonzeros() const {
  return (2 * d_[0].degree + 1) * (2 * d_[1].degree + 1) * (2 * d_[2].degree + 1);
}

double AffineVolumeOperator::entry(int i, int j, int k, int i0, int j0, int k0) const {
  const Direction &U = d_[0], &V = d_[1], &W = d_[2];
  const size_t wu = 2 * U.degree + 1, wv = 2 * V.degree + 1, ww = 2 * W.degree + 1;
  const size_t u = i * wu + (i0 - i + U.degree), ut = i0 * wu + (i - i0 + U.degree);
  const size_t v = j * wv + (j0 - j + V.degree), vt = j0 * wv + (j - j0 + V.degree);
  const size_t w = k * ww + (k0 - k + W.degree), wt = k0 * ww + (k - k0 + W.degree);
  double e = g_[0][0] * U.K[u] * V.M[v] * W.M[w] + g_[1][1] * U.M[u] * V.K[v] * W.M[w] + g_[2][2] * U.M[u] * V.M[v] * W.K[w] +
             r_ * U.M[u] * V.M[v] * W.M[w];
  // The mixed terms, G_ab (d_a on the row's function, d_b on the column's) + G_ba (the other way).
  if (g_[0][1] != 0) e += g_[0][1] * (U.D[u] * V.D[vt] + U.D[ut] * V.D[v]) * W.M[w];
  if (g_[0][2] != 0) e += g_[0][2] * (U.D[u] * W.D[wt] + U.D[ut] * W.D[w]) * V.M[v];
  if (g_[1][2] != 0) e += g_[1][2] * (V.D[v] * W.D[wt] + V.D[vt] * W.D[w]) * U.M[u];
  return e;
}

void AffineVolumeOperator::apply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
  if (x.size() != num_functions()) throw std::invalid_argument("AffineVolumeOperator::apply: wrong vector size");
  y.resize(x.size());
  // Slab by slab (apply_within): its work arrays are a slab's, where whole-array mode products
  // took three more vectors of the problem's size (0.4 GB at 256^3 hexahedra).
  apply_within(x.data(), FunctionBox{{0, 0, 0}, n_}, y.data());
}

AffineVolumeOperator::FunctionBox AffineVolumeOperator::free_box(const DofLayout& layout) const {
  FunctionBox box;
  if (layout.num_free() == 0) return box;
  const auto at = [&](int f) {
    return std::array<int, 3>{f % n_[0], (f / n_[0]) % n_[1], f / (n_[0] * n_[1])};
  };
  const std::array<int, 3> first = at(layout.function_of_dof.front()), last = at(layout.function_of_dof.back());
  for (int d = 0; d < 3; ++d) box.first[d] = first[d], box.count[d] = last[d] - first[d] + 1;
  return box;
}

bool AffineVolumeOperator::applies_free(const DofLayout& layout) const {
  // A tensor product of free univariate indices (numbered as the box numbers them), each a run.
  std::array<std::vector<int>, 3> free;
  if (!tensor_free_indices_3d(n_, layout, free)) return false;
  for (const std::vector<int>& f : free)
    if (f.empty() || f.back() - f.front() + 1 != static_cast<int>(f.size())) return false;
  return true;
}

void AffineVolumeOperator::apply_free(const DofLayout& layout, const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
  y.resize(x.size());
  apply_within(x.data(), free_box(layout), y.data());
}

Eigen::VectorXd AffineVolumeOperator::diagonal() const {
  Eigen::VectorXd out(num_functions());
#pragma omp parallel for schedule(static)
  for (int k = 0; k < n_[2]; ++k)
    for (int j = 0; j < n_[1]; ++j)
      for (int i = 0; i < n_[0]; ++i) out[i + n_[0] * (j + long(n_[1]) * k)] = entry(i, j, k, i, j, k);
  return out;
}

Eigen::VectorXd AffineVolumeOperator::load(const Expression& source) const {
  const Direction &U = d_[0], &V = d_[1], &W = d_[2];
  const int Pu = U.degree + 1, Pv = V.degree + 1, Pw = W.degree + 1, Qu = U.points, Qv = V.points, Qw = W.points;
  const int threads = omp_get_max_threads();
  // Each thread sums its slabs of elements into its own copy (neighbouring slabs share functions).
  std::vector<Eigen::VectorXd> partial(threads);
  const ExpressionBatch compiled(std::vector<Expression>{source});
  // The first cell (in the mesh's order, eu + n_eu (ev + n_ev ew)) where f is not finite.
  long bad_cell = std::numeric_limits<long>::max();
  double bad[3] = {0, 0, 0};
#pragma omp parallel
  {
    Eigen::VectorXd& out = partial[omp_get_thread_num()];
    out.setZero(num_functions());
    ExpressionBatch f(compiled);
    const int points = Qu * Qv * Qw;
    std::vector<double> x(points), y(points), z(points), h(points), t1(size_t(Qu) * Qv * Pw), t2(size_t(Qu) * Pv * Pw);
#pragma omp for schedule(static)
    for (int ew = 0; ew < W.elements; ++ew)
      for (int ev = 0; ev < V.elements; ++ev)
        for (int eu = 0; eu < U.elements; ++eu) {
          element_points(U, V, W, eu, ev, ew, x.data(), y.data(), z.data());
          f.evaluate(x.data(), y.data(), z.data(), points);
          const double* value = f.result(0);
          for (int c = 0; c < Qw; ++c)
            for (int b = 0; b < Qv; ++b)
              for (int a = 0; a < Qu; ++a) {
                const int q = a + Qu * (b + Qv * c);
                if (!std::isfinite(value[q])) {
                  const long cell = eu + long(U.elements) * (ev + long(V.elements) * ew);
#pragma omp critical(knotwork_affine_volume_bad_source)
                  if (cell < bad_cell) bad_cell = cell, bad[0] = x[q], bad[1] = y[q], bad[2] = z[q];
                }
                h[q] = value[q] * U.weight[eu * Qu + a] * V.weight[ev * Qv + b] * W.weight[ew * Qw + c] * det_;
              }
          // Sum over the points one direction at a time: w, then v, then u.
          for (int cw = 0; cw < Pw; ++cw)
            for (int b = 0; b < Qv; ++b)
              for (int a = 0; a < Qu; ++a) {
                double s = 0;
                for (int c = 0; c < Qw; ++c) s += W.value[(size_t(ew) * Qw + c) * Pw + cw] * h[a + Qu * (b + Qv * c)];
                t1[a + Qu * (b + size_t(Qv) * cw)] = s;
              }
          for (int cw = 0; cw < Pw; ++cw)
            for (int bv = 0; bv < Pv; ++bv)
              for (int a = 0; a < Qu; ++a) {
                double s = 0;
                for (int b = 0; b < Qv; ++b) s += V.value[(size_t(ev) * Qv + b) * Pv + bv] * t1[a + Qu * (b + size_t(Qv) * cw)];
                t2[a + Qu * (bv + size_t(Pv) * cw)] = s;
              }
          for (int cw = 0; cw < Pw; ++cw)
            for (int bv = 0; bv < Pv; ++bv)
              for (int au = 0; au < Pu; ++au) {
                double s = 0;
                for (int a = 0; a < Qu; ++a) s += U.value[(size_t(eu) * Qu + a) * Pu + au] * t2[a + Qu * (bv + size_t(Pv) * cw)];
                out[(U.first[eu] + au) + n_[0] * ((V.first[ev] + bv) + long(n_[1]) * (W.first[ew] + cw))] += s;
              }
        }
  }
  if (bad_cell != std::numeric_limits<long>::max()) {
    // Worded as the element loop words it (solver/assemble_poisson.cpp).
    const long eu = bad_cell % U.elements, ev = (bad_cell / U.elements) % V.elements, ew = bad_cell / (long(U.elements) * V.elements);
    std::ostringstream m;
    m << source.where() << ": source \"" << source.text() << "\" is not a finite number at (" << bad[0] << ", " << bad[1]
      << ", " << bad[2] << ") in cell " << bad_cell << " (u in [" << ends_[0][eu] << ", " << ends_[0][eu + 1]
      << "], v in [" << ends_[1][ev] << ", " << ends_[1][ev + 1] << "], w in [" << ends_[2][ew] << ", "
      << ends_[2][ew + 1] << "])";
    throw InputError(m.str());
  }
  Eigen::VectorXd out = std::move(partial[0]);
  for (int t = 1; t < threads; ++t) out += partial[t];
  return out;
}

bool AffineVolumeOperator::squared_errors(const Eigen::VectorXd& coefficients, const ExactSolution& exact, int points_u,
                                          int points_v, std::array<double, 2>& squares, Eigen::VectorXd* h1_per_cell,
                                          CellRange cells) const {
  if (coefficients.size() != num_functions()) throw std::invalid_argument("AffineVolumeOperator::squared_errors: wrong vector size");
  if (exact.u_z.empty()) throw std::invalid_argument("error norms on a volume need the exact solution as a function of (x, y, z)");
  const int requested[3] = {points_u, points_v, error_points_w_};
  std::array<Direction, 3> e;
  for (int k = 0; k < 3; ++k) e[k] = direction(space_[k], requested[k] > 0 ? requested[k] : space_[k].degree() + 2, false);
  const Direction &U = e[0], &V = e[1], &W = e[2];
  const int Pu = U.degree + 1, Pv = V.degree + 1, Pw = W.degree + 1, Qu = U.points, Qv = V.points, Qw = W.points;
  const Eigen::Matrix3d inverse_transpose = map_.jacobian.inverse().transpose();
  const long all = long(U.elements) * V.elements * W.elements;
  const long first = cells.first, last = cells.last < 0 ? all : cells.last;
  if (h1_per_cell) h1_per_cell->setZero(all);
  // Per slab of elements along w (one thread sums a slab), then the slabs in order: the totals do
  // not depend on the threads.
  std::vector<double> l2_slabs(W.elements, 0.0), h1_slabs(W.elements, 0.0);
  const ExpressionBatch compiled(std::vector<Expression>{exact.u, exact.u_x, exact.u_y, exact.u_z});
#pragma omp parallel
  {
    ExpressionBatch f(compiled);
    const int points = Qu * Qv * Qw;
    std::vector<double> x(points), y(points), z(points), c(size_t(Pu) * Pv * Pw);
    // Along u: (value, d/du) at (qa, b, cw); along v: (value, d/du, d/dv) at (qa, qb, cw); then w.
    std::vector<double> t1(size_t(2) * Qu * Pv * Pw), t2(size_t(3) * Qu * Qv * Pw);
#pragma omp for schedule(static)
    for (int ew = 0; ew < W.elements; ++ew)
      for (int ev = 0; ev < V.elements; ++ev)
        for (int eu = 0; eu < U.elements; ++eu) {
          const long cell = eu + long(U.elements) * (ev + long(V.elements) * ew);
          if (cell < first || cell >= last) continue;
          for (int cw = 0; cw < Pw; ++cw)
            for (int bv = 0; bv < Pv; ++bv)
              for (int au = 0; au < Pu; ++au)
                c[au + Pu * (bv + size_t(Pv) * cw)] =
                    coefficients[(U.first[eu] + au) + n_[0] * ((V.first[ev] + bv) + long(n_[1]) * (W.first[ew] + cw))];
          for (int bc = 0; bc < Pv * Pw; ++bc)
            for (int a = 0; a < Qu; ++a) {
              const double* value = &U.value[(size_t(eu) * Qu + a) * Pu];
              const double* derivative = &U.derivative[(size_t(eu) * Qu + a) * Pu];
              double s0 = 0, s1 = 0;
              for (int au = 0; au < Pu; ++au) s0 += value[au] * c[au + size_t(Pu) * bc], s1 += derivative[au] * c[au + size_t(Pu) * bc];
              t1[2 * (a + size_t(Qu) * bc)] = s0;
              t1[2 * (a + size_t(Qu) * bc) + 1] = s1;
            }
          for (int cw = 0; cw < Pw; ++cw)
            for (int b = 0; b < Qv; ++b) {
              const double* value = &V.value[(size_t(ev) * Qv + b) * Pv];
              const double* derivative = &V.derivative[(size_t(ev) * Qv + b) * Pv];
              for (int a = 0; a < Qu; ++a) {
                double s0 = 0, s1 = 0, s2 = 0;
                for (int bv = 0; bv < Pv; ++bv) {
                  const double* t = &t1[2 * (a + size_t(Qu) * (bv + size_t(Pv) * cw))];
                  s0 += value[bv] * t[0], s1 += value[bv] * t[1], s2 += derivative[bv] * t[0];
                }
                double* o = &t2[3 * (a + size_t(Qu) * (b + size_t(Qv) * cw))];
                o[0] = s0, o[1] = s1, o[2] = s2;
              }
            }
          element_points(U, V, W, eu, ev, ew, x.data(), y.data(), z.data());
          f.evaluate(x.data(), y.data(), z.data(), points);
          const double *u = f.result(0), *ux = f.result(1), *uy = f.result(2), *uz = f.result(3);
          double e0 = 0, e1 = 0;
          for (int l = 0; l < Qw; ++l) {
            const double* value = &W.value[(size_t(ew) * Qw + l) * Pw];
            const double* derivative = &W.derivative[(size_t(ew) * Qw + l) * Pw];
            for (int b = 0; b < Qv; ++b)
              for (int a = 0; a < Qu; ++a) {
                double uh = 0, gu = 0, gv = 0, gw = 0;
                for (int cw = 0; cw < Pw; ++cw) {
                  const double* t = &t2[3 * (a + size_t(Qu) * (b + size_t(Qv) * cw))];
                  uh += value[cw] * t[0], gu += value[cw] * t[1], gv += value[cw] * t[2], gw += derivative[cw] * t[0];
                }
                const Eigen::Vector3d g = inverse_transpose * Eigen::Vector3d(gu, gv, gw);
                const int q = a + Qu * (b + Qv * l);
                const double measure = U.weight[eu * Qu + a] * V.weight[ev * Qv + b] * W.weight[ew * Qw + l] * det_;
                const double d = u[q] - uh, dx = ux[q] - g[0], dy = uy[q] - g[1], dz = uz[q] - g[2];
                e0 += measure * d * d;
                e1 += measure * (dx * dx + dy * dy + dz * dz);
              }
          }
          l2_slabs[ew] += e0;
          h1_slabs[ew] += e1;
          if (h1_per_cell) (*h1_per_cell)[cell] = e1;
        }
  }
  squares = {0, 0};
  for (int ew = 0; ew < W.elements; ++ew) squares[0] += l2_slabs[ew], squares[1] += h1_slabs[ew];
  return true;
}

void AffineVolumeOperator::coupled_functions(int function, std::vector<int>& out) const {
  const int i0 = function % n_[0], j0 = (function / n_[0]) % n_[1], k0 = function / (n_[0] * n_[1]);
  for (int k = d_[2].low[k0]; k <= d_[2].high[k0]; ++k)
    for (int j = d_[1].low[j0]; j <= d_[1].high[j0]; ++j)
      for (int i = d_[0].low[i0]; i <= d_[0].high[i0]; ++i) out.push_back(i + n_[0] * (j + n_[1] * k));
}

void AffineVolumeOperator::row_entries(int row, int count, const int* columns, double* values) const {
  const int i = row % n_[0], j = (row / n_[0]) % n_[1], k = row / (n_[0] * n_[1]);
  for (int e = 0; e < count; ++e) {
    const int c = columns[e], i0 = c % n_[0], j0 = (c / n_[0]) % n_[1], k0 = c / (n_[0] * n_[1]);
    values[e] = std::abs(i - i0) <= d_[0].degree && std::abs(j - j0) <= d_[1].degree && std::abs(k - k0) <= d_[2].degree
                    ? entry(i, j, k, i0, j0, k0)
                    : 0.0;
  }
}

Eigen::SparseMatrix<double> AffineVolumeOperator::lower_matrix(const DofLayout& layout) const { return write_lower(layout, true); }

Eigen::SparseMatrix<double> AffineVolumeOperator::lower_pattern(const DofLayout& layout) const {
  return write_lower(layout, false);
}

Eigen::SparseMatrix<double> AffineVolumeOperator::write_lower(const DofLayout& layout, bool with_values) const {
  if (static_cast<long>(layout.dof.size()) != long(num_functions()))
    throw std::logic_error("AffineVolumeOperator::write_lower: a layout of another space");
  const Direction &U = d_[0], &V = d_[1], &W = d_[2];
  const int n = layout.num_free(), nu = n_[0], nv = n_[1];
  Eigen::SparseMatrix<double> K(n, n);
  int* outer = K.outerIndexPtr();
  outer[0] = 0;
  // Column d is function (i0, j0, k0); its rows are the free functions at or after it (function
  // order = dof order) that share an element with it: k from k0, then j from j0 on k0's layer,
  // then i from i0 on the column's own line of functions.
  const auto for_rows = [&](int d, auto row) {
    const int g = layout.function_of_dof[d], i0 = g % nu, j0 = (g / nu) % nv, k0 = g / (nu * nv);
    for (int k = k0; k <= W.high[k0]; ++k)
      for (int j = k == k0 ? j0 : V.low[j0]; j <= V.high[j0]; ++j)
        for (int i = k == k0 && j == j0 ? i0 : U.low[i0]; i <= U.high[i0]; ++i) {
          const int dof = layout.dof[i + nu * (j + long(nv) * k)];
          if (dof >= 0) row(dof, i0, j0, k0, i, j, k);
        }
  };
#pragma omp parallel for schedule(static)
  for (int d = 0; d < n; ++d) {
    int count = 0;
    for_rows(d, [&](int, int, int, int, int, int, int) { ++count; });
    outer[d + 1] = count;
  }
  for (int d = 0; d < n; ++d) outer[d + 1] += outer[d];
  K.resizeNonZeros(outer[n]);
  int* inner = K.innerIndexPtr();
  double* values = K.valuePtr();
#pragma omp parallel for schedule(static)
  for (int d = 0; d < n; ++d) {
    long at = outer[d];
    for_rows(d, [&](int dof, int i0, int j0, int k0, int i, int j, int k) {
      inner[at] = dof;
      values[at] = with_values ? entry(i, j, k, i0, j0, k0) : 0.0;
      ++at;
    });
  }
  return K;
}

}  // namespace knotwork
