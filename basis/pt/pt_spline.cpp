#include "basis/pt/pt_spline.hpp"

#include <algorithm>
#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <cmath>
#include <map>
#include <numeric>
#include <set>
#include <stdexcept>
#include <tuple>
#include <mutex>
#include <unordered_map>

#include "basis/tmesh/lr_spline.hpp"
#include "basis/tmesh/partition_topology.hpp"
#include "basis/pt/pt_eee.hpp"
#include "basis/exact/sparse_rank.hpp"
#include "basis/tmesh/spline_dimension.hpp"
#include "basis/tmesh/tmesh_conformality.hpp"

namespace knotwork {

using namespace pt_detail;

namespace {

// The partition with x and y exchanged.
RectangularPartition transposed(const RectangularPartition& mesh) {
  std::vector<RationalBox> cells;
  for (const auto& c : mesh.cells()) cells.push_back({c.y0, c.x0, c.y1, c.x1});
  return RectangularPartition(std::move(cells));
}

// Pairs (cell, grid line strictly inside it) for horizontal lines.
long horizontal_extended_edges(const RectangularPartition& mesh, const Grid& g) {
  long count = 0;
  for (const auto& c : mesh.cells()) count += g.index_y(c.y1) - g.index_y(c.y0) - 1;
  return count;
}


// Weighted B-spline coefficients of the functions of one block as rows of a sparse matrix,
// each row scaled to unit norm (scale[k] = 1 / norm of row k).
Eigen::SparseMatrix<double> weighted_rows(const std::vector<SparseVector>& F, const std::vector<double>& weight,
                                          std::vector<double>& scale) {
  std::vector<Eigen::Triplet<double>> t;
  scale.assign(F.size(), 0);
  for (size_t k = 0; k < F.size(); ++k) {
    double norm = 0;
    for (const auto& [col, v] : F[k]) norm += std::pow(v.get_d() * weight[col], 2);
    scale[k] = 1 / std::sqrt(norm);
    for (const auto& [col, v] : F[k]) t.emplace_back(static_cast<int>(k), col, v.get_d() * weight[col] * scale[k]);
  }
  Eigen::SparseMatrix<double> A(static_cast<Eigen::Index>(F.size()), static_cast<Eigen::Index>(weight.size()));
  A.setFromTriplets(t.begin(), t.end());
  return A;
}

// Gram eigenvalues below this (functions scaled to unit weighted norm) count as nearly
// dependent. On the halved test mesh of docs/PT_SPLINES.md the groups' smallest eigenvalues
// were 2.8e-11 to 6.8e-8 before the replacement and 9.8e-7 to 0.82 after.
constexpr double kNearlyDependent = 1e-7;

// Replaces nearly dependent functions of F (one group, see make_numerically_independent) by the
// nearly vanishing combinations themselves, normalized: each eigenvector v of the Gram matrix
// with eigenvalue below kNearlyDependent gives w = sum_k v_k f_k / |.|, which takes the place of
// one f_p with a large v_p (QR with column pivoting on the eigenvectors chooses the p). The v_k
// are rounded to rationals once (and those below 1e-9 of the largest dropped, the pivot kept),
// so every w is exactly in S(T) and the change of basis is exactly invertible (checked by a
// modular rank). Repeated while some eigenvalue is small, at most three times.
void condition_block(std::vector<SparseVector>& F, const std::vector<double>& weight) {
  const int N = static_cast<int>(F.size());
  if (N < 2) return;
  for (int pass = 0; pass < 3; ++pass) {
    std::vector<double> scale;
    const Eigen::SparseMatrix<double> A = weighted_rows(F, weight, scale);
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(Eigen::MatrixXd(A * A.transpose()));
    int near = 0;
    while (near < N && eig.eigenvalues()(near) < kNearlyDependent) ++near;
    if (near == 0) return;
    const Eigen::MatrixXd V = eig.eigenvectors().leftCols(near);
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(V.transpose());
    std::vector<SparseVector> replaced(near);
    for (int i = 0; i < near; ++i) {
      const int pivot = qr.colsPermutation().indices()(i);
      const double cut = 1e-9 * V.col(i).cwiseAbs().maxCoeff();
      SparseVector w;
      for (int k = 0; k < N; ++k)
        if (k == pivot || std::abs(V(k, i)) > cut) axpy(w, mpq_class(V(k, i) * scale[k]), F[k]);
      double norm = 0;
      for (const auto& [col, v] : w) norm += std::pow(v.get_d() * weight[col], 2);
      for (auto& [col, v] : w) v /= mpq_class(std::sqrt(norm));
      replaced[i] = std::move(w);
    }
    for (int i = 0; i < near; ++i) F[qr.colsPermutation().indices()(i)] = std::move(replaced[i]);
    std::vector<SparseRationalRow> rows;
    for (const auto& f : F) rows.push_back({{f.begin(), f.end()}});
    if (rank_reliable(rows, static_cast<long>(weight.size())) != N)
      throw std::logic_error("make_numerically_independent: the change of basis lost rank");
  }
}

// The construction with horizontal lines extended, on `mesh` as given.
PtSplineBasis build_horizontal(const RectangularPartition& mesh, int m, int n, const C0Lines& c0) {
  const Grid g = make_grid(mesh);
  PtSplineBasis B;
  B.m = m, B.n = n, B.extension = PtExtension::kHorizontal, B.c0 = c0;
  // Global y knots: every y-coordinate, simple, except the C^0 lines (multiplicity n).
  std::vector<mpq_class> interior_y;
  for (int iy = 1; iy < g.ny(); ++iy) interior_y.insert(interior_y.end(), contains(c0.y, g.Y[iy]) ? n : 1, g.Y[iy]);
  const std::vector<mpq_class> KY = open_knot_vector(interior_y, g.Y.front(), g.Y.back(), n);
  const int ny = static_cast<int>(KY.size()) - n - 1;
  std::vector<std::vector<int>> columns_of_row_spline(ny);  // spline indices per j
  for (int j = 0; j < ny; ++j) {
    const std::vector<mpq_class> ky(KY.begin() + j, KY.begin() + j + n + 2);
    const int s0 = g.index_y(ky.front()), s1 = g.index_y(ky.back());
    // Vertical lines of T across every strip of supp N_j.
    std::vector<mpq_class> interior_x;
    for (int ix = 1; ix < g.nx(); ++ix) {
      bool across = true;
      for (int s = s0; s < s1 && across; ++s) across = g.at(ix - 1, s) != g.at(ix, s);
      if (across) interior_x.insert(interior_x.end(), contains(c0.x, g.X[ix]) ? m : 1, g.X[ix]);
    }
    const std::vector<mpq_class> KX = open_knot_vector(interior_x, g.X.front(), g.X.back(), m);
    for (size_t i = 0; i + m + 1 < KX.size(); ++i) {
      columns_of_row_spline[j].push_back(static_cast<int>(B.splines.size()));
      B.splines.push_back({std::vector<mpq_class>(KX.begin() + i, KX.begin() + i + m + 2), ky});
    }
  }

  // EEE rows: for each cell of T and each grid line y = Y_k strictly inside it, the jump of
  // d^n/dy^n across Y_k, a polynomial of degree m in x on [x0, x1] (no knot of any M_{j,i}
  // lies inside a cell its support meets), vanishes at m + 1 points.
  std::vector<EeeRow> rows;
  for (const auto& c : mesh.cells()) {
    for (int k = g.index_y(c.y0) + 1; k < g.index_y(c.y1); ++k) {
      ++B.extended_edges;
      const mpq_class& yk = g.Y[k];
      std::vector<std::pair<int, mpq_class>> jumps;  // (j, jump of N_j^(n) at yk)
      for (int j = 0; j < ny; ++j) {
        if (KY[j] > yk || KY[j + n + 1] < yk) continue;  // an end knot jumps too
        const std::vector<mpq_class> ky(KY.begin() + j, KY.begin() + j + n + 2);
        mpq_class jump = top_derivative_jump(ky, yk);
        if (jump != 0) jumps.emplace_back(j, std::move(jump));
      }
      for (int q = 0; q <= m; ++q) {
        const mpq_class xq = c.x0 + (c.x1 - c.x0) * (q + 1) / (m + 2);
        std::vector<std::pair<int, mpq_class>> row;
        for (const auto& [j, jump] : jumps)
          for (int col : columns_of_row_spline[j]) {
            const auto& kx = B.splines[col].x;
            if (kx.front() >= xq || kx.back() <= xq) continue;
            mpq_class v = jump * bspline_value<mpq_class>(kx, xq);
            if (v != 0) row.emplace_back(col, std::move(v));
          }
        if (!row.empty()) rows.push_back(std::move(row));
      }
    }
  }
  eliminate_extended_edges(B, rows, g, mesh);
  return B;
}

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

struct PtBernsteinCache {
  std::vector<RationalBox> cells;  // the T-mesh they belong to
  // (B-spline index * cells + cell) -> Bernstein coefficients of its x and y factors there.
  std::unordered_map<long, std::pair<std::vector<mpq_class>, std::vector<mpq_class>>> factors;
};

namespace {

template <class S>
std::vector<std::vector<std::pair<int, std::vector<S>>>> cell_polynomials(const PtSplineBasis& B,
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
  std::vector<std::vector<std::pair<int, std::vector<S>>>> out(B.functions.size());
  // On a cell, a B-spline is N(x) M(y) with N, M each a polynomial on the sampled grid
  // interval; their Bernstein coefficients over the cell (extrapolated from that interval:
  // the functions, not each B-spline, are polynomials on the whole cell) are computed once
  // per (B-spline, cell), and a function's are the sum of coefficient * outer products.
  std::unordered_map<long, std::pair<std::vector<S>, std::vector<S>>> local;
  auto* bernstein = &local;
  std::unique_lock<std::mutex> cache_guard;
  if constexpr (std::is_same_v<S, mpq_class>) {
    cache_guard = std::unique_lock<std::mutex>(*B.bernstein_lock);
    auto same = [&](const std::vector<RationalBox>& cells) {
      return std::equal(cells.begin(), cells.end(), mesh.cells().begin(), mesh.cells().end(),
                        [](const RationalBox& a, const RationalBox& b) {
                          return a.x0 == b.x0 && a.y0 == b.y0 && a.x1 == b.x1 && a.y1 == b.y1;
                        });
    };
    if (!B.bernstein || !same(B.bernstein->cells))
      B.bernstein = std::make_shared<PtBernsteinCache>(PtBernsteinCache{mesh.cells(), {}});
    bernstein = &B.bernstein->factors;
  }
  auto univariate = [](const std::vector<std::vector<S>>& inv, const std::vector<S>& values) {
    std::vector<S> c(values.size(), S(0));
    for (size_t a = 0; a < values.size(); ++a)
      for (size_t q = 0; q < values.size(); ++q)
        if (values[q] != 0) c[a] += inv[a][q] * values[q];
    return c;
  };
  for (size_t f = 0; f < B.functions.size(); ++f) {
    std::map<int, std::vector<S>> coefficients;
    std::vector<int> seen;
    for (const auto& [s, coef] : B.functions[f]) {
      const auto& sp = B.splines[s];
      const S cf = to_scalar<S>(coef);
      seen.clear();
      for (int iy = g.index_y(sp.y.front()); iy < g.index_y(sp.y.back()); ++iy)
        for (int ix = g.index_x(sp.x.front()); ix < g.index_x(sp.x.back()); ++ix) {
          const int k = g.at(ix, iy);
          if (std::find(seen.begin(), seen.end(), k) != seen.end()) continue;
          seen.push_back(k);
          auto [cached, fresh_values] = bernstein->try_emplace(static_cast<long>(s) * mesh.num_cells() + k);
          if (fresh_values) {
            const CellSampling& cs = sampling[k];
            std::vector<S> vx(m + 1), vy(n + 1);
            for (int q = 0; q <= m; ++q) vx[q] = bspline_value<S>(sp.x, cs.px[q]);
            for (int q = 0; q <= n; ++q) vy[q] = bspline_value<S>(sp.y, cs.py[q]);
            cached->second = {univariate(cs.inv_x, vx), univariate(cs.inv_y, vy)};
          }
          const std::vector<S>&bx = cached->second.first, &by = cached->second.second;
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
      if (nonzero) out[f].emplace_back(k, std::move(C));
    }
  }
  return out;
}

}  // namespace

std::optional<PtExtension> parse_pt_extension(const std::string& name) {
  for (PtExtension e : {PtExtension::kAuto, PtExtension::kMinimal, PtExtension::kHorizontal, PtExtension::kVertical,
                        PtExtension::kDiagonalizable})
    if (name == pt_extension_name(e)) return e;
  return std::nullopt;
}

const char* pt_extension_name(PtExtension extension) {
  switch (extension) {
    case PtExtension::kAuto: return "auto";
    case PtExtension::kMinimal: return "minimal";
    case PtExtension::kHorizontal: return "horizontal";
    case PtExtension::kVertical: return "vertical";
    case PtExtension::kDiagonalizable: return "diagonalizable";
  }
  return "?";
}

namespace {

// Makes `B` a certified basis of S(T), or says why it cannot be one. Its functions lie in S(T)
// by construction. Their exact cell polynomials are eliminated modulo a prime, smallest
// support first, and each function that depends on the ones before it is dropped: the LR
// B-splines of T^e can be dependent and still span S(T^e) (on Dokken-Lyche-Pettersen's mesh
// they do, with T^e = T). The independent rest must be as many as the brute-force
// dimension. The ranks are modular (over Q when the two primes disagree), so a certificate
// is never wrong: dim <= unknowns - rank mod p (rank mod p <= rank over Q), and rows
// independent mod p are independent over Q.
std::string certify(PtSplineBasis& B, const RectangularPartition& mesh, long dimension) {
  const long count = static_cast<long>(B.functions.size());
  if (count < dimension) return std::to_string(count) + " functions for a space of dimension " + std::to_string(dimension);
  const long per_cell = static_cast<long>(B.m + 1) * (B.n + 1);
  const auto polynomials = cell_polynomials<mpq_class>(B, mesh);
  std::vector<long> order(count);
  std::iota(order.begin(), order.end(), 0L);
  std::stable_sort(order.begin(), order.end(),
                   [&](long a, long b) { return polynomials[a].size() < polynomials[b].size(); });
  std::vector<SparseRationalRow> rows;
  for (long f : order) {
    SparseRationalRow r;
    for (const auto& [k, coefficients] : polynomials[f])
      for (long a = 0; a < per_cell; ++a)
        if (coefficients[a] != 0) r.terms.emplace_back(k * per_cell + a, coefficients[a]);
    rows.push_back(std::move(r));
  }
  std::vector<bool> independent;
  const long rank = rank_reliable(rows, per_cell * mesh.num_cells(), &independent);
  if (rank != dimension)
    return "the " + std::to_string(count) + " functions have rank " + std::to_string(rank) +
           " for a space of dimension " + std::to_string(dimension);
  if (rank == count) return {};
  std::vector<bool> keep(count);
  for (long i = 0; i < count; ++i) keep[order[i]] = independent[i];
  std::vector<std::vector<std::pair<int, mpq_class>>> kept;
  int untouched = 0;
  for (long f = 0; f < count; ++f) {
    if (!keep[f]) continue;
    untouched += f < B.untouched;
    kept.push_back(std::move(B.functions[f]));
  }
  B.functions = std::move(kept);
  B.untouched = untouched;
  B.dropped_dependent = static_cast<int>(count - rank);
  return {};
}

// One attempt at the minimal extension: the certified basis, or why there is none. With
// `diagonalizable`, a T^e that fails the ordering test is refused too.
std::optional<PtSplineBasis> attempt_minimal(const RectangularPartition& mesh, int m, int n, const C0Lines& c0,
                                             const MinimalVariant& variant, long dimension, bool diagonalizable,
                                             std::string& why) {
  try {
    std::optional<PtSplineBasis> B = build_minimal(mesh, m, n, c0, variant);
    if (!B) {
      why = "an l-edge could not be inserted even as a full line";
      return std::nullopt;
    }
    if (diagonalizable &&
        !diagonalizable_by_ordering(partition_topology(RectangularPartition(B->extension_cells)), m, n)) {
      why = "no lengthening made T^e diagonalizable";
      return std::nullopt;
    }
    why = certify(*B, mesh, dimension);
    if (why.empty()) return B;
  } catch (const std::logic_error& e) {  // a block's modular rank fell below its rank over Q
    why = e.what();
  }
  return std::nullopt;
}

// T^e of a full extension: every cell of T cut at every y (horizontal) or x coordinate of T.
std::vector<RationalBox> full_extension_cells(const RectangularPartition& mesh, bool horizontal) {
  std::set<mpq_class> lines;
  for (const auto& c : mesh.cells()) lines.insert(horizontal ? c.y0 : c.x0);
  std::vector<RationalBox> cells;
  for (const auto& c : mesh.cells()) {
    const mpq_class start = horizontal ? c.y0 : c.x0, end = horizontal ? c.y1 : c.x1;
    std::vector<mpq_class> cuts{start};
    for (auto it = lines.upper_bound(start); it != lines.end() && *it < end; ++it) cuts.push_back(*it);
    cuts.push_back(end);
    for (size_t i = 0; i + 1 < cuts.size(); ++i)
      cells.push_back(horizontal ? RationalBox{c.x0, cuts[i], c.x1, cuts[i + 1]}
                                 : RationalBox{cuts[i], c.y0, cuts[i + 1], c.y1});
  }
  return cells;
}

}  // namespace

PtSplineBasis pt_spline_basis(const RectangularPartition& mesh, int m, int n, PtExtension extension, const C0Lines& c0) {
  if (m < 1 || n < 1) throw std::invalid_argument("PT-splines need degrees m, n >= 1");
  {
    const Grid g = make_grid(mesh);
    for (int dir = 0; dir < 2; ++dir)
      for (const mpq_class& v : dir == 0 ? c0.x : c0.y) {
        const auto& L = dir == 0 ? g.X : g.Y;
        const int i = dir == 0 ? g.index_x(v) : g.index_y(v);
        bool cut = i > 0 && i + 1 < static_cast<int>(L.size()) && L[i] == v;
        for (int s = 0; s < (dir == 0 ? g.ny() : g.nx()) && cut; ++s)
          cut = dir == 0 ? g.at(i - 1, s) != g.at(i, s) : g.at(s, i - 1) != g.at(s, i);
        if (!cut)
          throw std::invalid_argument(std::string("the C0 line ") + (dir == 0 ? "x = " : "y = ") + v.get_str() +
                                      " is not a line of the T-mesh from boundary to boundary");
      }
  }
  std::string refused;
  if (extension == PtExtension::kDiagonalizable) {
    const long dimension = spline_space_dimension(mesh, m, n, m - 1, n - 1, RankMethod::kModular, c0).dimension;
    const Grid g = make_grid(mesh);
    std::string why;
    for (int k = 0; k <= std::max(g.nx(), g.ny()); ++k)
      for (bool shortest : {false, true})
        if (auto B = attempt_minimal(mesh, m, n, c0, MinimalVariant{shortest, k}, dimension, true, why)) {
          B->extension = PtExtension::kDiagonalizable;
          return std::move(*B);
        }
    throw std::runtime_error("diagonalizable PT-spline extension: " + why);
  }
  if (extension == PtExtension::kAuto || extension == PtExtension::kMinimal) {
    const long dimension = spline_space_dimension(mesh, m, n, m - 1, n - 1, RankMethod::kModular, c0).dimension;
    for (const MinimalVariant variant : {MinimalVariant{false, 0}, MinimalVariant{true, 0}, MinimalVariant{false, 1},
                                         MinimalVariant{true, 1}}) {
      std::string why;
      if (auto B = attempt_minimal(mesh, m, n, c0, variant, dimension, false, why)) return std::move(*B);
      if (refused.empty()) refused = why + " (and in the three other insertion orders)";  // the first reason
    }
    if (extension == PtExtension::kMinimal) throw std::runtime_error("minimal PT-spline extension: " + refused);
  }
  const RectangularPartition flipped = transposed(mesh);
  if (extension == PtExtension::kAuto) {
    const long h = horizontal_extended_edges(mesh, make_grid(mesh));
    const long v = horizontal_extended_edges(flipped, make_grid(flipped));
    extension = v < h ? PtExtension::kVertical : PtExtension::kHorizontal;
  }
  if (extension == PtExtension::kHorizontal) {
    PtSplineBasis B = build_horizontal(mesh, m, n, c0);
    B.minimal_refused = refused;
    B.extension_cells = full_extension_cells(mesh, true);
    return B;
  }
  PtSplineBasis B = build_horizontal(flipped, n, m, C0Lines{c0.y, c0.x});
  for (auto& s : B.splines) std::swap(s.x, s.y);
  std::swap(B.m, B.n);
  B.c0 = c0;
  B.extension = PtExtension::kVertical;
  B.minimal_refused = refused;
  B.extension_cells = full_extension_cells(mesh, false);
  return B;
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

namespace knotwork {

namespace {

// Echelon elimination that keeps the functions whose `key` vectors are independent (in the
// order given) and reduces the others to zero key: `on_dependent(i, reduced function)`.
// Functions with a zero key are left as they are. The result spans the same space.
template <class OnDependent>
void eliminate(const std::vector<SparseVector>& keys, const std::vector<SparseVector>& functions,
               OnDependent on_dependent) {
  SparseEchelon echelon;
  for (size_t i = 0; i < keys.size(); ++i) {
    if (keys[i].empty()) continue;
    SparseVector key = keys[i], full = functions[i];
    if (!echelon.add(key, full)) on_dependent(i, full);
  }
}

}  // namespace

namespace {

// Each function's trace on the boundary of the rectangle, in coordinates (side, B-spline of
// the side's knot vector): the union, with the largest multiplicity, of the knot vectors of
// the traces on that side. The traces are refined into it by knot insertion: with the LR
// B-splines of the minimal extension two traces need not be windows of one knot vector.
std::vector<SparseVector> trace_keys(const PtSplineBasis& B, const RectangularPartition& mesh) {
  const Grid g = make_grid(mesh);
  const mpq_class &x0 = g.X.front(), &x1 = g.X.back(), &y0 = g.Y.front(), &y1 = g.Y.back();
  auto all_equal = [](const std::vector<mpq_class>& t, size_t from, size_t to, const mpq_class& v) {
    for (size_t i = from; i < to; ++i)
      if (t[i] != v) return false;
    return true;
  };
  std::vector<std::vector<std::pair<int, const std::vector<mpq_class>*>>> traces(B.splines.size());
  std::map<mpq_class, long> multiplicity[4];
  for (size_t s = 0; s < B.splines.size(); ++s) {
    const auto& sp = B.splines[s];
    auto add = [&](int side, const std::vector<mpq_class>& along) {
      traces[s].emplace_back(side, &along);
      for (const mpq_class& v : along) {
        long& mult = multiplicity[side][v];
        mult = std::max<long>(mult, std::count(along.begin(), along.end(), v));
      }
    };
    if (all_equal(sp.y, 0, B.n + 1, y0)) add(0, sp.x);
    if (all_equal(sp.x, 1, B.m + 2, x1)) add(1, sp.y);
    if (all_equal(sp.y, 1, B.n + 2, y1)) add(2, sp.x);
    if (all_equal(sp.x, 0, B.m + 1, x0)) add(3, sp.y);
  }
  std::vector<mpq_class> fine[4];
  for (int side = 0; side < 4; ++side)
    for (const auto& [v, mult] : multiplicity[side]) fine[side].insert(fine[side].end(), mult, v);
  std::map<std::pair<int, int>, int> coordinate;  // (side, window) -> id, by first use
  std::vector<SparseVector> trace_of(B.splines.size());
  for (size_t s = 0; s < B.splines.size(); ++s)
    for (const auto& [side, along] : traces[s])
      for (const auto& [window, c] : refine_bspline(*along, fine[side])) {
        const auto it = coordinate.emplace(std::make_pair(side, window), static_cast<int>(coordinate.size())).first;
        axpy(trace_of[s], c, SparseVector{{it->second, mpq_class(1)}});
      }
  std::vector<SparseVector> keys;
  for (const auto& f : B.functions) {
    SparseVector key;
    for (const auto& [s, c] : f) axpy(key, c, trace_of[s]);
    keys.push_back(std::move(key));
  }
  return keys;
}

}  // namespace

void make_boundary_traces_independent(PtSplineBasis& B, const RectangularPartition& mesh) {
  std::vector<SparseVector> keys = trace_keys(B, mesh), functions;
  for (const auto& f : B.functions) functions.push_back(SparseVector(f.begin(), f.end()));
  // Functions with the simplest traces become the pivots: a dependent trace is then reduced by
  // subtracting its own trace coefficients' worth of functions with one trace B-spline each,
  // and no coefficient grows. (In the order of the basis, pivots were arbitrary and reduced
  // functions reached Bernstein coefficients of 1e12 on a halved T-mesh.)
  std::vector<size_t> order(keys.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return std::make_pair(keys[a].size(), functions[a].size()) < std::make_pair(keys[b].size(), functions[b].size());
  });
  std::vector<SparseVector> sorted_keys, sorted_functions;
  for (size_t i : order) sorted_keys.push_back(keys[i]), sorted_functions.push_back(functions[i]);
  eliminate(sorted_keys, sorted_functions,
            [&](size_t i, const SparseVector& reduced) { B.functions[order[i]] = as_function(reduced); });
}

int make_non_negative(PtSplineBasis& B, const RectangularPartition& mesh) {
  const Grid g = make_grid(mesh);
  // Cross-cuts of T: lines from boundary to boundary.
  std::vector<mpq_class> cx, cy;
  for (int ix = 1; ix < g.nx(); ++ix) {
    bool cut = true;
    for (int s = 0; s < g.ny() && cut; ++s) cut = g.at(ix - 1, s) != g.at(ix, s);
    if (cut) cx.insert(cx.end(), contains(B.c0.x, g.X[ix]) ? B.m : 1, g.X[ix]);
  }
  for (int iy = 1; iy < g.ny(); ++iy) {
    bool cut = true;
    for (int s = 0; s < g.nx() && cut; ++s) cut = g.at(s, iy - 1) != g.at(s, iy);
    if (cut) cy.insert(cy.end(), contains(B.c0.y, g.Y[iy]) ? B.n : 1, g.Y[iy]);
  }
  const auto KX = open_knot_vector(cx, g.X.front(), g.X.back(), B.m), KY = open_knot_vector(cy, g.Y.front(), g.Y.back(), B.n);
  const int first_cross = static_cast<int>(B.splines.size());
  std::vector<std::vector<std::pair<int, mpq_class>>> cross;
  for (size_t j = 0; j + B.n + 1 < KY.size(); ++j)
    for (size_t i = 0; i + B.m + 1 < KX.size(); ++i) {
      cross.push_back({{static_cast<int>(B.splines.size()), mpq_class(1)}});
      B.splines.push_back({std::vector<mpq_class>(KX.begin() + i, KX.begin() + i + B.m + 2),
                           std::vector<mpq_class>(KY.begin() + j, KY.begin() + j + B.n + 2)});
    }
  // Exchange: the cross-cut B-splines first, then the functions independent of what precedes.
  PtSplineBasis all = B;
  all.functions = cross;
  all.functions.insert(all.functions.end(), B.functions.begin(), B.functions.end());
  const auto poly = pt_cell_polynomials_exact(all, mesh);
  const int per_cell = (B.m + 1) * (B.n + 1);
  std::vector<SparseVector> keys, functions;
  for (size_t f = 0; f < all.functions.size(); ++f) {
    SparseVector key, full;
    for (const auto& [k, c] : poly[f])
      for (int a = 0; a < per_cell; ++a)
        if (c[a] != 0) key[k * per_cell + a] = c[a];
    for (const auto& [s, c] : all.functions[f]) full[s] = c;
    keys.push_back(std::move(key));
    functions.push_back(std::move(full));
  }
  std::vector<bool> dropped(all.functions.size(), false);
  eliminate(keys, functions, [&](size_t i, const SparseVector&) { dropped[i] = true; });
  std::vector<std::vector<std::pair<int, mpq_class>>> kept = cross;
  std::vector<size_t> kept_from;  // index in `all` (and `poly`) of each kept function
  for (size_t f = 0; f < cross.size(); ++f) kept_from.push_back(f);
  for (size_t f = cross.size(); f < all.functions.size(); ++f)
    if (!dropped[f]) kept.push_back(all.functions[f]), kept_from.push_back(f);
  if (kept.size() != B.functions.size())
    throw std::logic_error("make_non_negative: the cross-cut B-splines are not in the span of the basis (" +
                           std::to_string(cross.size()) + " cross-cut, " + std::to_string(kept.size()) + " kept of " +
                           std::to_string(all.functions.size()) + ")");
  // Lift: f + c * (sum of the cross-cut B-splines over the cells where f lives) >= 0.
  for (size_t f = cross.size(); f < kept.size(); ++f) {
    mpq_class lowest = 0;
    std::set<int> cells;
    for (const auto& [k, c] : poly[kept_from[f]]) {
      cells.insert(k);
      for (const auto& v : c) lowest = std::min(lowest, v);
    }
    if (lowest >= 0) continue;
    SparseVector full;
    for (const auto& [s, c] : kept[f]) full[s] = c;
    for (size_t k = 0; k < cross.size(); ++k) {
      const auto& sp = B.splines[first_cross + static_cast<int>(k)];
      bool meets = false;
      for (int cell : cells) {
        const auto& c = mesh.cells()[cell];
        meets = meets || (sp.x.front() < c.x1 && c.x0 < sp.x.back() && sp.y.front() < c.y1 && c.y0 < sp.y.back());
      }
      if (meets) axpy(full, -lowest, SparseVector{{first_cross + static_cast<int>(k), mpq_class(1)}});
    }
    kept[f] = as_function(full);
  }
  B.functions = std::move(kept);
  return static_cast<int>(cross.size());
}

}  // namespace knotwork

namespace knotwork {

void make_numerically_independent(PtSplineBasis& B, const RectangularPartition& mesh) {
  const std::vector<SparseVector> keys = trace_keys(B, mesh);
  std::vector<double> weight(B.splines.size());
  for (size_t s = 0; s < B.splines.size(); ++s) {
    const auto& sp = B.splines[s];
    weight[s] = std::sqrt(mpq_class((sp.x.back() - sp.x.front()) * (sp.y.back() - sp.y.front())).get_d());
  }
  // Groups: functions sharing B-splines, the ones vanishing on the boundary apart from the
  // others, so that a combination keeps its group's traces (zero, or independent).
  const int N = static_cast<int>(B.functions.size());
  UnionFind uf(N);
  std::map<std::pair<bool, int>, int> first_user;
  for (int f = 0; f < N; ++f)
    for (const auto& [s, c] : B.functions[f]) {
      const auto [it, fresh] = first_user.emplace(std::make_pair(keys[f].empty(), s), f);
      if (!fresh) uf.join(f, it->second);
    }
  std::map<int, std::vector<int>> groups;
  for (int f = 0; f < N; ++f) groups[uf.find(f)].push_back(f);
  for (const auto& [root, members] : groups) {
    if (members.size() < 2) continue;
    std::vector<SparseVector> F;
    for (int f : members) F.push_back(SparseVector(B.functions[f].begin(), B.functions[f].end()));
    condition_block(F, weight);
    for (size_t a = 0; a < members.size(); ++a) B.functions[members[a]] = as_function(F[a]);
  }
}

mpq_class pt_evaluate(const PtSplineBasis& B, int f, const mpq_class& x, const mpq_class& y) {
  mpq_class v = 0;
  for (const auto& [s, c] : B.functions[f]) {
    const auto& sp = B.splines[s];
    if (x < sp.x.front() || x >= sp.x.back() || y < sp.y.front() || y >= sp.y.back()) continue;
    v += c * bspline_value<mpq_class>(sp.x, x) * bspline_value<mpq_class>(sp.y, y);
  }
  return v;
}

namespace {

// d^k/ds^k of the Bernstein polynomial with coefficients b (degree p) at s, on [0, 1].
double bernstein_derivative(std::vector<double> b, int k, double s) {
  int p = static_cast<int>(b.size()) - 1;
  for (int d = 0; d < k; ++d, --p) {
    for (int i = 0; i < p; ++i) b[i] = p * (b[i + 1] - b[i]);
    b.pop_back();
  }
  if (b.empty()) return 0;
  for (int level = static_cast<int>(b.size()) - 1; level > 0; --level)
    for (int i = 0; i < level; ++i) b[i] = (1 - s) * b[i] + s * b[i + 1];
  return b[0];
}

}  // namespace

double pt_smoothness_residual(const PtCellPolynomials& polys, const RectangularPartition& mesh, int m, int n,
                              const C0Lines& c0) {
  const auto& edges = mesh.shared_edges();
  std::vector<std::vector<int>> edges_of_cell(mesh.num_cells());
  for (size_t e = 0; e < edges.size(); ++e) {
    edges_of_cell[edges[e].first].push_back(static_cast<int>(e));
    edges_of_cell[edges[e].second].push_back(static_cast<int>(e));
  }
  const std::vector<double> zero((m + 1) * (n + 1), 0.0);
  double worst = 0;
  for (const auto& f : polys) {
    std::map<int, const std::vector<double>*> on;
    std::set<int> near;  // edges of the cells where f lives
    double scale = 0;
    for (const auto& [k, c] : f) {
      on[k] = &c;
      near.insert(edges_of_cell[k].begin(), edges_of_cell[k].end());
      for (double v : c) scale = std::max(scale, std::abs(v));
    }
    if (scale == 0) continue;
    for (int index : near) {
      const auto& e = edges[index];
      const int pn = e.vertical ? m : n, pt = e.vertical ? n : m;  // degree across / along
      const int orders = contains(e.vertical ? c0.x : c0.y, e.position) ? 1 : pn;  // derivatives kept
      const int points = m + n + 2;
      double h[2];
      const std::vector<double>* b[2];
      for (int side = 0; side < 2; ++side) {
        const int cell = side == 0 ? e.first : e.second;
        const auto& box = mesh.cells()[cell];
        h[side] = mpq_class(e.vertical ? box.x1 - box.x0 : box.y1 - box.y0).get_d();
        const auto it = on.find(cell);
        b[side] = it == on.end() ? &zero : it->second;
      }
      for (int q = 0; q < points; ++q) {
        const mpq_class t = e.from + (e.to - e.from) * (q + 1) / (points + 1);
        // Each cell polynomial restricted to the line through the point across the edge: a
        // univariate Bernstein polynomial in the normal direction.
        std::vector<double> normal[2];
        for (int side = 0; side < 2; ++side) {
          const auto& box = mesh.cells()[side == 0 ? e.first : e.second];
          const double along = e.vertical ? mpq_class((t - box.y0) / (box.y1 - box.y0)).get_d()
                                          : mpq_class((t - box.x0) / (box.x1 - box.x0)).get_d();
          normal[side].resize(pn + 1);
          std::vector<double> line(pt + 1);
          for (int i = 0; i <= pn; ++i) {
            for (int j = 0; j <= pt; ++j) line[j] = e.vertical ? (*b[side])[i + (m + 1) * j] : (*b[side])[j + (m + 1) * i];
            normal[side][i] = bernstein_derivative(line, 0, along);
          }
        }
        // Derivatives 0 .. pn-1 must match; each jump relative to the scale of a k-th
        // derivative on the smaller of the two cells.
        const double h_min = std::min(h[0], h[1]);
        for (int k = 0; k < orders; ++k) {
          const double left = bernstein_derivative(normal[0], k, 1.0) / std::pow(h[0], k);
          const double right = bernstein_derivative(normal[1], k, 0.0) / std::pow(h[1], k);
          worst = std::max(worst, std::abs(left - right) * std::pow(h_min, k) / scale);
        }
      }
    }
  }
  return worst;
}

}  // namespace knotwork
