// Each PT-spline's Bernstein coefficients on each T-mesh cell, exactly (GMP rationals) or in
// floating point: the B-splines' x and y factors interpolated per cell (cached exactly, under
// the basis's lock), combined with the basis's coefficients.
#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <set>
#include <stdexcept>
#include <unordered_map>

#include "basis/exact/sparse_rank.hpp"
#include "basis/tmesh/lr_spline.hpp"
#include "basis/tmesh/partition_topology.hpp"
#include "basis/pt/pt_eee.hpp"
#include "basis/pt/pt_spline.hpp"
#include <mutex>
#include <type_traits>

namespace knotwork {

using namespace pt_detail;

namespace {

template <class S>
S magnitude(const S& v) {
  return v < 0 ? S(-v) : v;
}

template <class S>
S to_scalar(const mpq_class& v) {
  if constexpr (std::is_same_v<S, double>) return v.get_d();
  else return v;
}

// Inverse of the Bernstein collocation matrix of degree p at points s_q (q = 0..p).
template <class S>
std::vector<std::vector<S>> inverse_bernstein_collocation(int p, const std::vector<S>& s) {
  std::vector<std::vector<S>> A(p + 1, std::vector<S>(2 * (p + 1), S(0)));
  std::vector<S> binom(p + 1, S(1));
  for (int a = 1; a <= p; ++a) binom[a] = binom[a - 1] * (p - a + 1) / a;
  for (int q = 0; q <= p; ++q) {
    for (int a = 0; a <= p; ++a) {
      S v = binom[a];
      for (int e = 0; e < a; ++e) v *= s[q];
      for (int e = 0; e < p - a; ++e) v *= (1 - s[q]);
      A[q][a] = v;
    }
    A[q][p + 1 + q] = 1;
  }
  for (int col = 0; col <= p; ++col) {  // Gauss-Jordan with partial pivoting
    int piv = col;
    for (int r = col + 1; r <= p; ++r)
      if (magnitude(A[r][col]) > magnitude(A[piv][col])) piv = r;
    std::swap(A[col], A[piv]);
    const S d = A[col][col];
    for (auto& v : A[col]) v /= d;
    for (int r = 0; r <= p; ++r) {
      if (r == col || A[r][col] == 0) continue;
      const S f = A[r][col];
      for (int k = 0; k < 2 * (p + 1); ++k) A[r][k] -= f * A[col][k];
    }
  }
  std::vector<std::vector<S>> inv(p + 1, std::vector<S>(p + 1));
  for (int a = 0; a <= p; ++a)
    for (int q = 0; q <= p; ++q) inv[a][q] = A[a][p + 1 + q];
  return inv;
}

}  // namespace

namespace {

// The Bernstein coefficients of B-spline factors over cells, one direction: they depend only
// on the factor's knots and on the cell's interval in that direction (which also fixes the
// sampled grid interval), so B-splines with the same x knots share them along a whole row of
// cells. On a 8228-cell degree-3 mesh that shares each factor among about 10 (B-spline, cell)
// pairs; the exact factors were most of the time of the cell polynomials.
template <class S>
struct UnivariateFactors {
  std::map<std::vector<int>, int> knot_ids;  // knots as grid indices -> id
  std::vector<int> spline_knots;             // B-spline index -> id of its knots here
  std::unordered_map<uint64_t, std::vector<S>> coefficients;  // (id << 32) | interval -> Bernstein coefficients
};

}  // namespace

struct PtBernsteinCache {
  std::vector<RationalBox> cells;  // the T-mesh they belong to
  UnivariateFactors<mpq_class> factors[2];  // x, y
};

namespace {

// S: the arithmetic; Out: what is kept (S, or double rounded once from exact S: each
// function's exact polynomials are then dropped as soon as they are rounded, so a large
// mesh never holds all of them at once, about 1 GB at 50 000 bicubic cells).
template <class S, class Out = S>
std::vector<std::vector<std::pair<int, std::vector<Out>>>> cell_polynomials(const PtSplineBasis& B,
                                                                           const RectangularPartition& mesh) {
  const Grid g = make_grid(mesh);
  const int m = B.m, n = B.n;
  // Per cell: the largest grid interval inside it in each direction (every B-spline is a
  // polynomial on each grid cell), the sample points there and the inverse collocations.
  struct CellSampling {
    std::vector<S> px, py;
    std::vector<std::vector<S>> inv_x, inv_y;
  };
  std::vector<CellSampling> sampling(mesh.num_cells());
  for (int k = 0; k < mesh.num_cells(); ++k) {
    const auto& c = mesh.cells()[k];
    auto largest = [](const std::vector<mpq_class>& L, int i0, int i1) {
      int best = i0;
      for (int i = i0; i < i1; ++i)
        if (L[i + 1] - L[i] > L[best + 1] - L[best]) best = i;
      return best;
    };
    const int bx = largest(g.X, g.index_x(c.x0), g.index_x(c.x1)), by = largest(g.Y, g.index_y(c.y0), g.index_y(c.y1));
    CellSampling& cs = sampling[k];
    std::vector<S> sx, sy;
    for (int q = 0; q <= m; ++q) {
      const mpq_class x = g.X[bx] + (g.X[bx + 1] - g.X[bx]) * (q + 1) / (m + 2);
      cs.px.push_back(to_scalar<S>(x));
      sx.push_back(to_scalar<S>(mpq_class((x - c.x0) / (c.x1 - c.x0))));
    }
    for (int q = 0; q <= n; ++q) {
      const mpq_class y = g.Y[by] + (g.Y[by + 1] - g.Y[by]) * (q + 1) / (n + 2);
      cs.py.push_back(to_scalar<S>(y));
      sy.push_back(to_scalar<S>(mpq_class((y - c.y0) / (c.y1 - c.y0))));
    }
    cs.inv_x = inverse_bernstein_collocation<S>(m, sx);
    cs.inv_y = inverse_bernstein_collocation<S>(n, sy);
  }
  std::vector<std::vector<std::pair<int, std::vector<Out>>>> out(B.functions.size());
  // On a cell, a B-spline is N(x) M(y) with N, M each a polynomial on the sampled grid
  // interval; their Bernstein coefficients over the cell (extrapolated from that interval:
  // the functions, not each B-spline, are polynomials on the whole cell) are computed once
  // per (B-spline, cell), and a function's are the sum of coefficient * outer products.
  auto univariate = [](const std::vector<std::vector<S>>& inv, const std::vector<S>& values) {
    std::vector<S> c(values.size(), S(0));
    for (size_t a = 0; a < values.size(); ++a)
      for (size_t q = 0; q < values.size(); ++q)
        if (values[q] != 0) c[a] += inv[a][q] * values[q];
    return c;
  };
  UnivariateFactors<S> local[2];
  UnivariateFactors<S>* factors = local;
  std::unique_lock<std::mutex> cache_guard;
  if constexpr (std::is_same_v<S, mpq_class>) {
    cache_guard = std::unique_lock<std::mutex>(*B.bernstein_lock);
    auto same = [&](const std::vector<RationalBox>& cells) {
      return std::equal(cells.begin(), cells.end(), mesh.cells().begin(), mesh.cells().end(),
                        [](const RationalBox& a, const RationalBox& b) {
                          return a.x0 == b.x0 && a.y0 == b.y0 && a.x1 == b.x1 && a.y1 == b.y1;
                        });
    };
    if (!B.bernstein || !same(B.bernstein->cells)) {
      B.bernstein = std::make_shared<PtBernsteinCache>();
      B.bernstein->cells = mesh.cells();
    }
    factors = B.bernstein->factors;
  }
  // The id of B-spline s's knots in direction d (interned once per B-spline).
  auto knots_id = [&](int s, int d) {
    UnivariateFactors<S>& u = factors[d];
    while (u.spline_knots.size() <= static_cast<size_t>(s)) {
      const auto& knots = d == 0 ? B.splines[u.spline_knots.size()].x : B.splines[u.spline_knots.size()].y;
      std::vector<int> key;
      for (const mpq_class& t : knots) key.push_back(d == 0 ? g.index_x(t) : g.index_y(t));
      u.spline_knots.push_back(u.knot_ids.try_emplace(std::move(key), static_cast<int>(u.knot_ids.size())).first->second);
    }
    return u.spline_knots[s];
  };
  // Bernstein coefficients of the factor of B-spline s in direction d over cell k.
  auto factor = [&](int s, int d, int k) -> const std::vector<S>& {
    const auto& c = mesh.cells()[k];
    const uint64_t interval = d == 0 ? static_cast<uint64_t>(g.index_x(c.x0)) * (g.X.size() + 1) + g.index_x(c.x1)
                                     : static_cast<uint64_t>(g.index_y(c.y0)) * (g.Y.size() + 1) + g.index_y(c.y1);
    const uint64_t key = (static_cast<uint64_t>(knots_id(s, d)) << 32) | interval;
    auto [it, fresh] = factors[d].coefficients.try_emplace(key);
    if (fresh) {
      const CellSampling& cs = sampling[k];
      const auto& knots = d == 0 ? B.splines[s].x : B.splines[s].y;
      const auto& points = d == 0 ? cs.px : cs.py;
      std::vector<S> values;
      for (const S& t : points) values.push_back(bspline_value<S>(knots, t));
      it->second = univariate(d == 0 ? cs.inv_x : cs.inv_y, values);
    }
    return it->second;
  };
  for (size_t f = 0; f < B.functions.size(); ++f) {
    std::map<int, std::vector<S>> coefficients;
    for (const auto& [s, coef] : B.functions[f]) {
      const auto& sp = B.splines[s];
      const S cf = to_scalar<S>(coef);
      for (int k : g.cells_in(g.index_x(sp.x.front()), g.index_y(sp.y.front()), g.index_x(sp.x.back()), g.index_y(sp.y.back()))) {
          const std::vector<S>&bx = factor(s, 0, k), &by = factor(s, 1, k);
          bool any_x = false, any_y = false;
          for (const S& v : bx) any_x = any_x || v != 0;
          for (const S& v : by) any_y = any_y || v != 0;
          if (!any_x || !any_y) continue;
          auto [it, fresh] = coefficients.try_emplace(k);
          if (fresh) it->second.assign((m + 1) * (n + 1), S(0));
          std::vector<S>& C = it->second;
          for (int b = 0; b <= n; ++b) {
            if (by[b] == 0) continue;
            const S cb = cf * by[b];
            for (int a = 0; a <= m; ++a)
              if (bx[a] != 0) C[a + (m + 1) * b] += cb * bx[a];
          }
        }
    }
    for (auto& [k, C] : coefficients) {
      bool nonzero = false;
      S scale = 0;
      for (const S& c : C)
        if (magnitude(c) > scale) scale = magnitude(c);
      if constexpr (std::is_same_v<S, double>) {
        // Cancellation leaves rounding noise where the function vanishes on the cell.
        double fscale = 0;
        for (const auto& [s, coef] : B.functions[f]) fscale += magnitude(coef.get_d());
        nonzero = scale > 1e-13 * fscale;
      } else {
        nonzero = scale != 0;
      }
      if (!nonzero) continue;
      if constexpr (std::is_same_v<S, Out>) {
        out[f].emplace_back(k, std::move(C));
      } else {
        std::vector<Out> rounded;
        for (const S& v : C) rounded.push_back(v.get_d());
        out[f].emplace_back(k, std::move(rounded));
      }
    }
  }
  return out;
}

}  // namespace

PtCellPolynomialsExact pt_cell_polynomials_exact(const PtSplineBasis& basis, const RectangularPartition& mesh) {
  return cell_polynomials<mpq_class>(basis, mesh);
}

PtCellPolynomials pt_cell_polynomials_rounded(const PtSplineBasis& basis, const RectangularPartition& mesh) {
  return cell_polynomials<mpq_class, double>(basis, mesh);
}

PtCellPolynomials pt_cell_polynomials(const PtSplineBasis& basis, const RectangularPartition& mesh) {
  return cell_polynomials<double>(basis, mesh);
}

PtCellPolynomials to_double(const PtCellPolynomialsExact& exact) {
  PtCellPolynomials out(exact.size());
  for (size_t f = 0; f < exact.size(); ++f)
    for (const auto& [k, c] : exact[f]) {
      std::vector<double> d;
      for (const auto& v : c) d.push_back(v.get_d());
      out[f].emplace_back(k, std::move(d));
    }
  return out;
}

}  // namespace knotwork
