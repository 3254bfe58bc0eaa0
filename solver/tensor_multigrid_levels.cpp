#include "solver/tensor_multigrid_levels.hpp"

#include <Eigen/Eigenvalues>
#include <omp.h>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "solver/fast_diagonalization.hpp"
#include "solver/tensor_multigrid.hpp"

namespace knotwork {
namespace multigrid_levels {

namespace {

// Windows of `block` indices covering 0..n-1, the first one `offset` long when offset > 0; a
// last window shorter than block / 2 joins the one before (every window stays longer than p,
// so windows two apart never couple).
std::vector<std::pair<int, int>> tile(int n, int block, int offset) {
  std::vector<std::pair<int, int>> w;
  int s = 0;
  if (offset > 0 && offset < n) w.emplace_back(0, s = offset);
  while (s < n) {
    const int e = std::min(n, s + block);
    w.emplace_back(s, e - s);
    s = e;
  }
  if (w.size() > 1 && w.back().second < block / 2) {
    w[w.size() - 2].second += w.back().second;
    w.pop_back();
  }
  return w;
}

}  // namespace

double reaction_shift(const Eigen::VectorXd& a1, const Direction& u, const Direction& v, const Direction* w) {
  const int ru = u.basis.degree(), rv = v.basis.degree(), rw = w ? w->basis.degree() : 0, nw = w ? w->count : 1;
  double reaction = 0, model = 0;
  for (int c = rw; c < nw - rw; ++c)
    for (int b = rv; b < v.count - rv; ++b)
      for (int a = ru; a < u.count - ru; ++a) {
        reaction += a1[a + long(u.count) * (b + long(v.count) * c)];
        model += u.mass_row_sum[a] * v.mass_row_sum[b] * (w ? w->mass_row_sum[c] : 1.0);
      }
  return model > 0 && reaction > 0 ? reaction / model : 0.0;
}

void build_windows(Direction& d, int block, int tilings) {
  const UnivariatePair pair =
      univariate_pair(d.basis, d.mass_weight, d.stiffness_weight, d.nitsche_start, d.nitsche_end, d.nitsche_factor);
  const Eigen::VectorXd m = pair.mass.diagonal(), k = pair.stiffness.diagonal();
  d.mass_diagonal = m.segment(d.first, d.count);
  d.stiffness_diagonal = k.segment(d.first, d.count);
  d.mass_row_sum = (pair.mass * Eigen::VectorXd::Ones(pair.mass.cols())).segment(d.first, d.count);
  d.tilings.assign(tilings, {});
  for (int t = 0; t < tilings; ++t)
    for (const auto& [begin, size] : tile(d.count, block, t == 0 ? 0 : block / 2)) {
      Window w;
      w.begin = begin;
      w.size = size;
      const int f = d.first + begin;
      const Eigen::MatrixXd K = pair.stiffness.block(f, f, size, size), M = pair.mass.block(f, f, size, size);
      Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(K, M);
      if (es.info() != Eigen::Success)
        throw std::runtime_error("multigrid: a univariate mass block is not positive definite");
      w.U = es.eigenvectors();
      w.lambda = es.eigenvalues();
      d.tilings[t].push_back(std::move(w));
    }
}

Direction coarser(const Direction& fine, bool& halved, RowMatrix& prolongation) {
  Direction c = fine;
  c.tilings.clear();
  halved = halved_basis(fine.basis, c.basis);
  if (!halved) {
    prolongation.resize(fine.count, fine.count);
    prolongation.setIdentity();
    return c;
  }
  c.count = c.basis.num_functions() - c.first - c.fixed_at_end;
  // Coarse element e is fine elements 2e and 2e + 1: the fit's weights are log-linear, so their
  // geometric mean.
  auto merge = [](const std::vector<double>& w) {
    std::vector<double> out;
    for (size_t e = 0; e + 1 < w.size(); e += 2) out.push_back(std::sqrt(w[e] * w[e + 1]));
    return out;
  };
  if (!fine.mass_weight.empty()) c.mass_weight = merge(fine.mass_weight);
  if (!fine.stiffness_weight.empty()) c.stiffness_weight = merge(fine.stiffness_weight);
  const RowMatrix T = refinement_matrix(c.basis, fine.basis);
  prolongation = T.block(fine.first, c.first, fine.count, c.count);
  prolongation.makeCompressed();
  return c;
}

bool free_range(const std::vector<int>& free, int n, Direction& d) {
  if (free.empty() || free.back() - free.front() + 1 != static_cast<int>(free.size())) return false;
  if (free.front() > 1 || free.back() < n - 2) return false;
  d.first = free.front();
  d.count = static_cast<int>(free.size());
  d.fixed_at_end = n - 1 - free.back();
  return true;
}

void solve_in_eigenbases(const Window& U, const Window& V, Eigen::MatrixXd& R, Eigen::MatrixXd& T, double shift) {
  T.noalias() = U.U.transpose() * R;
  R.noalias() = T * V.U;
  for (int j = 0; j < V.size; ++j)
    for (int i = 0; i < U.size; ++i) R(i, j) /= U.lambda[i] + V.lambda[j] + shift;
  T.noalias() = U.U * R;
  R.noalias() = T * V.U.transpose();
}

void solve_in_eigenbases(const Window& U, const Window& V, const Window& W, Eigen::VectorXd& R, Eigen::VectorXd& T,
                         double shift) {
  const int su = U.size, sv = V.size, sw = W.size;
  using Map = Eigen::Map<Eigen::MatrixXd>;
  // T = (U_w (x) U_v (x) U_u)^T R, one mode at a time.
  Map(T.data(), su, long(sv) * sw).noalias() = U.U.transpose() * Map(R.data(), su, long(sv) * sw);
  for (int l = 0; l < sw; ++l)
    Map(R.data() + long(su) * sv * l, su, sv).noalias() = Map(T.data() + long(su) * sv * l, su, sv) * V.U;
  Map(T.data(), long(su) * sv, sw).noalias() = Map(R.data(), long(su) * sv, sw) * W.U;
  for (int l = 0, at = 0; l < sw; ++l)
    for (int j = 0; j < sv; ++j)
      for (int i = 0; i < su; ++i, ++at) T[at] /= U.lambda[i] + V.lambda[j] + W.lambda[l] + shift;
  // R = (U_w (x) U_v (x) U_u) T.
  Map(R.data(), su, long(sv) * sw).noalias() = U.U * Map(T.data(), su, long(sv) * sw);
  for (int l = 0; l < sw; ++l)
    Map(T.data() + long(su) * sv * l, su, sv).noalias() = Map(R.data() + long(su) * sv * l, su, sv) * V.U.transpose();
  Map(R.data(), long(su) * sv, sw).noalias() = Map(T.data(), long(su) * sv, sw) * W.U.transpose();
}

// At 2048^2, p = 2, the V-cycles took 17% less time with 16 than with 32, in the same
// iterations; at p = 6 (256^2, square) 16 took 9 iterations where 32 took 7 (docs/SOLVERS.md).
int block_side(int asked, int p) { return asked > 0 ? std::max(asked, 2 * p + 2) : std::max(16, 5 * p + 2); }

// Row d is its strictly lower part, entry (d, j) read from column j of the triangle by binary
// search, j running over the tensor neighbours below d in ascending order, followed by column d
// of the triangle. Gathered row by row and threaded: a scatter of the triangle into rows
// (Eigen's selfadjointView conversion, or by hand) took 4-13 s at 4.2M dofs, p = 2, against
// 0.19 s at 1M (page-table misses over a 1.3 GB array).
// Filled in place: assigning the returned matrix cost 7.5 s at 4.2M dofs (Eigen 3.4's
// SparseMatrix copies where it could move).
void whole_from_lower(const Eigen::SparseMatrix<double>& L, int n0, int n1, const std::array<int, 3>& degree, RowMatrix& A) {
  const int n = static_cast<int>(L.rows());
  const long layer = static_cast<long>(n0) * n1;
  const int* start = L.outerIndexPtr();
  const int* row = L.innerIndexPtr();
  const double* value = L.valuePtr();
  const int pu = degree[0], pv = degree[1], pw = degree[2];
  // Visits the strictly lower entries of row d, ascending: f(column, value).
  auto lower_row = [&](int d, auto&& f) {
    const int a = d % n0, b = static_cast<int>((d / n0) % n1), c = static_cast<int>(d / layer);
    for (int c2 = std::max(0, c - pw); c2 <= c; ++c2)
      for (int b2 = std::max(0, b - pv); b2 <= std::min(n1 - 1, b + pv); ++b2) {
        if (c2 == c && b2 > b) break;
        for (int a2 = std::max(0, a - pu); a2 <= std::min(n0 - 1, a + pu); ++a2) {
          const int j = static_cast<int>(a2 + n0 * (b2 + static_cast<long>(n1) * c2));
          if (j >= d) break;
          const int* at = std::lower_bound(row + start[j], row + start[j + 1], d);
          if (at != row + start[j + 1] && *at == d) f(j, value[at - row]);
        }
      }
  };
  std::vector<int> count(n + 1, 0);
#pragma omp parallel for schedule(static)
  for (int d = 0; d < n; ++d) {
    int c = start[d + 1] - start[d];
    lower_row(d, [&](int, double) { ++c; });
    count[d + 1] = c;
  }
  for (int d = 0; d < n; ++d) count[d + 1] += count[d];
  // Every strictly lower entry found from its row: the pattern stays within the tensor
  // neighbourhood (functions more than a degree apart never share a cell).
  if (count[n] != 2 * static_cast<long>(L.nonZeros()) - n)
    throw std::logic_error("multigrid: the matrix couples functions more than a degree apart, or lacks a diagonal entry");
  A.resize(n, n);
  A.resizeNonZeros(count[n]);
  std::copy(count.begin(), count.end(), A.outerIndexPtr());
  int* col = A.innerIndexPtr();
  double* val = A.valuePtr();
#pragma omp parallel for schedule(static)
  for (int d = 0; d < n; ++d) {
    int at = count[d];
    lower_row(d, [&](int j, double v) { col[at] = j, val[at++] = v; });
    for (int k = start[d]; k < start[d + 1]; ++k, ++at) col[at] = row[k], val[at] = value[k];
  }
}

namespace {

// Row by row of the result (rows_by_accumulation): coarse row r sums P(i, I) A(fine row, x2)
// P(x2_dir, K) over the fine rows of column I of P (along dir) and their entries, x2_dir the
// entry's index along dir. `dir` a constant: with it at run time the loop took 1.7-1.9 times as
// long at 1M dofs, p = 2 (its index arrays stayed in memory).
template <int dir>
void galerkin_grid(const RowMatrix& A, const std::array<int, 3>& n, const RowMatrix& P, RowMatrix& B) {
  const Eigen::SparseMatrix<double> columns = P;
  std::array<int, 3> m = n;
  m[dir] = static_cast<int>(P.cols());
  const long nn = long(m[0]) * m[1] * m[2];
  // (Scalars, not the arrays: a store to `seen`, a char, may alias any array the loop reads.)
  const int f0 = n[0], f1 = n[1], m0 = m[0], m1 = m[1];
  const long fine_stride = dir == 0 ? 1 : dir == 1 ? f0 : long(f0) * f1;
  const long coarse_stride = dir == 0 ? 1 : dir == 1 ? m0 : long(m0) * m1;
  const auto split = [](long i, int d0, int d1) -> std::array<int, 3> {
    const long q = i / d0;
    return {static_cast<int>(i - q * d0), static_cast<int>(q % d1), static_cast<int>(q / d1)};
  };
  const auto join = [](const std::array<int, 3>& at, int d0, int d1) -> long {
    return at[0] + long(d0) * (at[1] + long(d1) * at[2]);
  };
  rows_by_accumulation(nn, B, [&](long r, auto&& add) {
    // Row r's fine rows and an entry's coarse columns differ from a base index only along dir:
    // base + stride * index.
    std::array<int, 3> at = split(r, m0, m1);
    const int own = at[dir];
    at[dir] = 0;
    const long fine_base = join(at, f0, f1);
    for (Eigen::SparseMatrix<double>::InnerIterator p(columns, own); p; ++p) {
      for (RowMatrix::InnerIterator a(A, fine_base + fine_stride * p.row()); a; ++a) {
        std::array<int, 3> to = split(a.col(), f0, f1);
        const int along = to[dir];
        to[dir] = 0;
        const long base = join(to, m0, m1);
        const double w = p.value() * a.value();
        for (RowMatrix::InnerIterator q(P, along); q; ++q) add(base + coarse_stride * q.col(), w * q.value());
      }
    }
  });
}

}  // namespace

void galerkin_direction(const RowMatrix& A, const std::array<int, 3>& n, const RowMatrix& P, int dir, RowMatrix& B) {
  if (dir == 0) galerkin_grid<0>(A, n, P, B);
  else if (dir == 1) galerkin_grid<1>(A, n, P, B);
  else galerkin_grid<2>(A, n, P, B);
}

}  // namespace multigrid_levels
}  // namespace knotwork
