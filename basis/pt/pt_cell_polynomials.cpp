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
#include "basis/pt/pt_bezier_mesh.hpp"
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

// The Bernstein coefficients over cell k of the factor of B-spline s in direction d, in the
// arithmetic S (exact factors are kept in the basis's cache, under its lock, for as long as
// this object lives). On a cell a B-spline is N(x) M(y) with N, M each a polynomial on the
// largest grid interval inside the cell; their coefficients over the cell are extrapolated
// from that interval: the functions, not each B-spline, are polynomials on the whole cell.
template <class S>
class CellFactors {
 public:
  CellFactors(const PtSplineBasis& B, const RectangularPartition& mesh) : B_(B), g_(make_grid(mesh)) {
    factors_ = local_;
    if constexpr (std::is_same_v<S, mpq_class>) {
      guard_ = std::unique_lock<std::mutex>(*B.bernstein_lock);
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
      factors_ = B.bernstein->factors;
    }
  }
  // The T cells the support of B-spline s meets, in increasing order.
  std::vector<int> cells_of(int s) const { return g_.cells_under(B_.splines[s]); }
  const std::vector<S>& factor(int s, int d, int k) {
    const auto& box = g_.cell_box[k];
    const int lo = box[d], hi = box[d + 2];
    const uint64_t interval = static_cast<uint64_t>(lo) * ((d == 0 ? g_.X.size() : g_.Y.size()) + 1) + hi;
    const uint64_t key = (static_cast<uint64_t>(knots_id(s, d)) << 32) | interval;
    auto [it, fresh] = factors_[d].coefficients.try_emplace(key);
    if (fresh) {
      const Sampling& sampling = sampling_of(d, lo, hi, interval);
      const auto& knots = d == 0 ? B_.splines[s].x : B_.splines[s].y;
      std::vector<S> values;
      for (const S& t : sampling.points) values.push_back(bspline_value<S>(knots, t));
      std::vector<S> c(values.size(), S(0));
      for (size_t a = 0; a < values.size(); ++a)
        for (size_t q = 0; q < values.size(); ++q)
          if (values[q] != 0) c[a] += sampling.inverse[a][q] * values[q];
      it->second = std::move(c);
    }
    return it->second;
  }

 private:
  // One direction of a cell interval [L[lo], L[hi]]: the sample points in its largest grid
  // interval and the inverse of the Bernstein collocation there.
  struct Sampling {
    std::vector<S> points;
    std::vector<std::vector<S>> inverse;
  };
  const Sampling& sampling_of(int d, int lo, int hi, uint64_t interval) {
    auto [it, fresh] = sampling_[d].try_emplace(interval);
    if (!fresh) return it->second;
    const std::vector<mpq_class>& L = d == 0 ? g_.X : g_.Y;
    const int p = d == 0 ? B_.m : B_.n;
    int best = lo;
    for (int i = lo; i < hi; ++i)
      if (L[i + 1] - L[i] > L[best + 1] - L[best]) best = i;
    std::vector<S> s;
    for (int q = 0; q <= p; ++q) {
      const mpq_class x = L[best] + (L[best + 1] - L[best]) * (q + 1) / (p + 2);
      it->second.points.push_back(to_scalar<S>(x));
      s.push_back(to_scalar<S>(mpq_class((x - L[lo]) / (L[hi] - L[lo]))));
    }
    it->second.inverse = inverse_bernstein_collocation<S>(p, s);
    return it->second;
  }
  // The id of B-spline s's knots in direction d (interned once per B-spline).
  int knots_id(int s, int d) {
    UnivariateFactors<S>& u = factors_[d];
    while (u.spline_knots.size() <= static_cast<size_t>(s)) {
      const auto& knots = d == 0 ? B_.splines[u.spline_knots.size()].x : B_.splines[u.spline_knots.size()].y;
      std::vector<int> key;
      for (const mpq_class& t : knots) key.push_back(d == 0 ? g_.index_x(t) : g_.index_y(t));
      u.spline_knots.push_back(u.knot_ids.try_emplace(std::move(key), static_cast<int>(u.knot_ids.size())).first->second);
    }
    return u.spline_knots[s];
  }

  const PtSplineBasis& B_;
  const Grid g_;
  UnivariateFactors<S> local_[2];
  UnivariateFactors<S>* factors_;
  std::unordered_map<uint64_t, Sampling> sampling_[2];
  std::unique_lock<std::mutex> guard_;
};

template <class S>
bool all_zero(const std::vector<S>& v) {
  return std::all_of(v.begin(), v.end(), [](const S& x) { return x == 0; });
}

// C += cf * (by outer bx), C indexed a + (m + 1) b.
template <class S>
void add_product(std::vector<S>& C, const S& cf, const std::vector<S>& bx, const std::vector<S>& by) {
  const size_t m1 = bx.size();
  for (size_t b = 0; b < by.size(); ++b) {
    if (by[b] == 0) continue;
    const S cb = cf * by[b];
    for (size_t a = 0; a < m1; ++a)
      if (bx[a] != 0) C[a + m1 * b] += cb * bx[a];
  }
}

// Whether the coefficients C of function f on a cell are not zero: exactly, or in floating
// point above the rounding noise cancellation leaves where the function vanishes.
template <class S>
bool nonzero(const std::vector<S>& C, const std::vector<std::pair<int, mpq_class>>& f) {
  S scale = 0;
  for (const S& c : C)
    if (magnitude(c) > scale) scale = magnitude(c);
  if constexpr (std::is_same_v<S, double>) {
    double fscale = 0;
    for (const auto& [s, coef] : f) fscale += magnitude(coef.get_d());
    return scale > 1e-13 * fscale;
  } else {
    return scale != 0;
  }
}

template <class S>
std::vector<std::vector<std::pair<int, std::vector<S>>>> cell_polynomials(const PtSplineBasis& B,
                                                                         const RectangularPartition& mesh) {
  CellFactors<S> factors(B, mesh);
  const int nb = (B.m + 1) * (B.n + 1);
  std::vector<std::vector<std::pair<int, std::vector<S>>>> out(B.functions.size());
  for (size_t f = 0; f < B.functions.size(); ++f) {
    std::map<int, std::vector<S>> coefficients;
    for (const auto& [s, coef] : B.functions[f]) {
      const S cf = to_scalar<S>(coef);
      for (int k : factors.cells_of(s)) {
        const std::vector<S>&bx = factors.factor(s, 0, k), &by = factors.factor(s, 1, k);
        if (all_zero(bx) || all_zero(by)) continue;
        auto [it, fresh] = coefficients.try_emplace(k);
        if (fresh) it->second.assign(nb, S(0));
        add_product(it->second, cf, bx, by);
      }
    }
    for (auto& [k, C] : coefficients)
      if (nonzero(C, B.functions[f])) out[f].emplace_back(k, std::move(C));
  }
  return out;
}

}  // namespace

void pt_detail::for_each_cell_polynomials_rounded(
    const PtSplineBasis& B, const RectangularPartition& mesh,
    const std::function<void(int cell, const std::vector<int>& functions, Eigen::MatrixXd& coefficients)>& visit) {
  CellFactors<mpq_class> factors(B, mesh);
  const int nb = (B.m + 1) * (B.n + 1);
  // Which B-splines meet each cell and which functions use each B-spline, both as CSR.
  auto to_csr = [](auto& lists, std::vector<int>& start, auto& items) {
    start.assign(1, 0);
    for (auto& l : lists) {
      items.insert(items.end(), l.begin(), l.end());
      start.push_back(static_cast<int>(items.size()));
      l = {};
    }
  };
  std::vector<int> cell_start, spline_start;
  std::vector<int> cell_splines;                   // B-splines
  std::vector<std::pair<int, int>> spline_uses;  // (function, term)
  {
    std::vector<std::vector<std::pair<int, int>>> uses(B.splines.size());
    std::vector<std::vector<int>> meets(mesh.num_cells());
    for (size_t f = 0; f < B.functions.size(); ++f)
      for (size_t t = 0; t < B.functions[f].size(); ++t)
        uses[B.functions[f][t].first].emplace_back(static_cast<int>(f), static_cast<int>(t));
    for (size_t s = 0; s < B.splines.size(); ++s)
      if (!uses[s].empty())
        for (int k : factors.cells_of(static_cast<int>(s))) meets[k].push_back(static_cast<int>(s));
    to_csr(uses, spline_start, spline_uses);
    to_csr(meets, cell_start, cell_splines);
  }
  std::map<int, std::vector<mpq_class>> coefficients;  // function -> exact coefficients on the cell
  std::vector<int> ids;
  for (int k = 0; k < mesh.num_cells(); ++k) {
    coefficients.clear();
    for (int i = cell_start[k]; i < cell_start[k + 1]; ++i) {
      const int s = cell_splines[i];
      const std::vector<mpq_class>&bx = factors.factor(s, 0, k), &by = factors.factor(s, 1, k);
      if (all_zero(bx) || all_zero(by)) continue;
      for (int u = spline_start[s]; u < spline_start[s + 1]; ++u) {
        const auto [f, t] = spline_uses[u];
        auto [it, fresh] = coefficients.try_emplace(f);
        if (fresh) it->second.assign(nb, mpq_class(0));
        add_product(it->second, B.functions[f][t].second, bx, by);
      }
    }
    ids.clear();
    for (const auto& [f, C] : coefficients)
      if (nonzero(C, B.functions[f])) ids.push_back(f);
    Eigen::MatrixXd rounded(ids.size(), nb);
    for (size_t r = 0; r < ids.size(); ++r) {
      const std::vector<mpq_class>& C = coefficients[ids[r]];
      for (int i = 0; i < nb; ++i) rounded(r, i) = C[i].get_d();
    }
    visit(k, ids, rounded);
  }
}

PtCellPolynomialsExact pt_cell_polynomials_exact(const PtSplineBasis& basis, const RectangularPartition& mesh) {
  return cell_polynomials<mpq_class>(basis, mesh);
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
