// Changes of basis that keep the span of a PT-spline basis: boundary traces made independent
// (exactly, for the Dirichlet projection), the non-negative basis of Prop. 1, and numerical
// conditioning block by block (weighted orthogonalization within groups sharing B-splines).
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

namespace knotwork {

using namespace pt_detail;

namespace {

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

}  // namespace

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

}  // namespace knotwork
