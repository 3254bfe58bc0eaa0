#pragma once
// What the geometric multigrids of tensor-product spaces share, bivariate (tensor_multigrid)
// and trivariate (tensor_multigrid_3d): one direction of one level (its basis, free range,
// separable weights and the smoother's windows with their eigenbases), its coarsening by
// dropping every other breakpoint, and the sparse steps on a grid of functions numbered
// a + n0 (b + n1 c): the whole matrix from its lower triangle, and the Galerkin product with a
// prolongation along one direction. Internal to those two files (and their tests).
#include <Eigen/SparseCore>
#include <omp.h>
#include <algorithm>
#include <array>
#include <utility>
#include <vector>

#include "basis/core/bspline_basis.hpp"

namespace knotwork {
namespace multigrid_levels {

using RowMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor>;

// A run of free univariate indices and the generalized eigenbasis of its principal block of
// the direction's (K, M): U^T M U = I, U^T K U = diag(lambda).
struct Window {
  int begin = 0, size = 0;
  Eigen::MatrixXd U;
  Eigen::VectorXd lambda;
};

// One direction of one level: its basis, free range, element weights of the separable
// operator, and the windows of each tiling.
struct Direction {
  BSplineBasis1D basis;
  int first = 0, count = 0;  // free functions first..first + count - 1
  int fixed_at_end = 0;      // 1 when the last function is not free
  std::vector<double> mass_weight, stiffness_weight;
  bool nitsche_start = false, nitsche_end = false;
  double nitsche_factor = 2;
  Eigen::VectorXd mass_diagonal, stiffness_diagonal;  // over the free functions
  Eigen::VectorXd mass_row_sum;  // M 1 over the free functions (a reaction's share of A 1)
  std::vector<std::vector<Window>> tilings;
};

// The windows of `tilings` tilings (the second shifted by block / 2) and the direction's
// diagonals and mass row sums over its free functions.
void build_windows(Direction& d, int block, int tilings);

// The coarser direction (halved when it can be: `halved` says) and its prolongation over the
// free functions (fine count x coarse count; the identity when not halved).
Direction coarser(const Direction& fine, bool& halved, RowMatrix& prolongation);

// The free range of one direction, from its free indices (contiguous, missing at most the first
// and the last function); false otherwise.
bool free_range(const std::vector<int>& free, int n, Direction& d);

// The block side: as given (at least 2p + 2), else max(16, 5p + 2).
int block_side(int asked, int p);

// The shift that stands for a reaction term c u in a level's separable operator, which knows
// only the geometry. Stiffness matrices annihilate constants, so on the rows whose couplings all
// lie among the free functions (at least each direction's degree from its ends), A 1 is the
// reaction's part alone, whatever the diffusion; the shift makes shift (M_u 1) (x) (M_v 1)
// (x) (M_w 1) match it there in the mean. `a1` is A 1 over the level's free functions (u
// fastest); `w` null on a plane. 0 where A 1 shows no reaction.
double reaction_shift(const Eigen::VectorXd& a1, const Direction& u, const Direction& v, const Direction* w = nullptr);

// A block smoother's local solve on the functions of windows U x V: R (U.size x V.size, the
// scaled residual) := (U.U (x) V.U) diag(1 / (lambda_u + lambda_v)) (U.U (x) V.U)^T R, the
// inverse of the block's separable operator in its eigenbases; T is work space.
void solve_in_eigenbases(const Window& U, const Window& V, Eigen::MatrixXd& R, Eigen::MatrixXd& T, double shift = 0);
// The same on a volume's block U x V x W: R holds U.size x V.size x W.size values, the first
// index fastest; T (as long) is work space. In both, `shift` adds shift M_u (x) M_v (x) M_w to
// the separable operator (the identity in the eigenbases): a reaction term.
void solve_in_eigenbases(const Window& U, const Window& V, const Window& W, Eigen::VectorXd& R, Eigen::VectorXd& T,
                         double shift = 0);

inline double row_dot(const RowMatrix& A, long row, const double* x) {
  const int* col = A.innerIndexPtr();
  const double* val = A.valuePtr();
  double s = 0;
  for (int k = A.outerIndexPtr()[row]; k < A.outerIndexPtr()[row + 1]; ++k) s += val[k] * x[col[k]];
  return s;
}

// The whole symmetric matrix, row-major, from its lower triangle (column-major), for functions
// a + n0 (b + n1 c) that couple only within degree[d] indices per direction (a bivariate grid:
// n1 = rows / n0 and degree[2] = 0).
void whole_from_lower(const Eigen::SparseMatrix<double>& L, int n0, int n1, const std::array<int, 3>& degree, RowMatrix& A);

// B (nn x nn, row-major) filled row by row, threaded: fill(r, add) calls add(column, value) for
// the terms of row r (a column may come many times: the terms add up, into a dense
// accumulator over the columns). Each thread keeps a contiguous range of rows in its own
// buffers, copied into B at its offset (one small vector per row cost more in allocation than
// the products).
// (`columns`: B's columns, when B is not square.)
template <class Fill>
void rows_by_accumulation(long nn, RowMatrix& B, Fill&& fill, long columns = -1) {
  const long nc = columns >= 0 ? columns : nn;
  B.resize(nn, nc);
  std::vector<long> row_start(nn + 1, 0);
#pragma omp parallel
  {
    const int threads = omp_get_num_threads(), t = omp_get_thread_num();
    const long first = nn * t / threads, last = nn * (t + 1) / threads;
    std::vector<double> sum(nc, 0.0), my_vals;
    std::vector<char> seen(nc, 0);
    std::vector<int> touched, my_cols;
    my_cols.reserve(static_cast<size_t>(last - first) * 30);
    my_vals.reserve(my_cols.capacity());
    const auto add = [&](long k, double v) {
      if (!seen[k]) seen[k] = 1, touched.push_back(static_cast<int>(k));
      sum[k] += v;
    };
    for (long r = first; r < last; ++r) {
      fill(r, add);
      std::sort(touched.begin(), touched.end());
      for (int c : touched) my_cols.push_back(c), my_vals.push_back(sum[c]), sum[c] = 0.0, seen[c] = 0;
      row_start[r + 1] = static_cast<long>(touched.size());
      touched.clear();
    }
#pragma omp barrier
#pragma omp single
    {
      for (long r = 0; r < nn; ++r) row_start[r + 1] += row_start[r];
      B.resizeNonZeros(row_start[nn]);
      for (long r = 0; r <= nn; ++r) B.outerIndexPtr()[r] = static_cast<int>(row_start[r]);
    }
    std::copy(my_cols.begin(), my_cols.end(), B.innerIndexPtr() + row_start[first]);
    std::copy(my_vals.begin(), my_vals.end(), B.valuePtr() + row_start[first]);
  }
}

// Q^T A Q for Q the prolongation P (fine x coarse) along direction `dir` of a grid of
// n[0] x n[1] x n[2] functions and the identity along the others (the bivariate multigrid
// keeps a version of its own, faster for two directions).
void galerkin_direction(const RowMatrix& A, const std::array<int, 3>& n, const RowMatrix& P, int dir, RowMatrix& B);

}  // namespace multigrid_levels
}  // namespace knotwork
