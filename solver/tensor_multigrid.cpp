#include "solver/tensor_multigrid.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>
#include <omp.h>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "solver/tensor_multigrid_levels.hpp"
#include "solver/tensor_rediscretize.hpp"

namespace knotwork {

double tensor_multigrid_bytes(double functions, int p, int q, bool with_matrix) {
  const double vectors = functions * 8 * 6 * 4 / 3;
  if (!with_matrix) return vectors + functions * 24 * 2;
  return functions * double(2 * p + 1) * (2 * q + 1) * 12 * 4 / 3 + functions * 8 * 6;
}

bool halved_basis(const BSplineBasis1D& fine, BSplineBasis1D& coarse) {
  const std::vector<double> b = fine.breakpoints();
  const std::vector<int> m = fine.multiplicities();
  const int elements = static_cast<int>(b.size()) - 1;
  if (elements < 2 || elements % 2 != 0 || !fine.is_open()) return false;
  const int p = fine.degree();
  std::vector<double> knots;
  for (int k = 0; k <= elements; k += 2) knots.insert(knots.end(), k == 0 || k == elements ? p + 1 : m[k], b[k]);
  coarse = BSplineBasis1D(p, std::move(knots));
  return true;
}

namespace {

using namespace multigrid_levels;

struct Level {
  Direction u, v;
  RowMatrix A;            // the whole matrix over this level's free dofs, a + count_u b
  // Or, without a matrix, the level's operator and its free functions (a box of them).
  std::shared_ptr<const TensorPoissonOperator> op;
  TensorPoissonOperator::FunctionBox free;
  Eigen::VectorXd scale;  // D^{-1/2}, D = diag(A) / diag(P)
  double shift = 0;       // P's reaction term: shift M_u (x) M_v (reaction_shift)
  RowMatrix Pu, Pv;       // from the next coarser level (empty on the coarsest)
  long size() const { return static_cast<long>(u.count) * v.count; }
};

// The next coarser level's directions and f's prolongations; false (and none) when neither
// direction halves.
bool coarsen(Level& f, Direction& u, Direction& v, bool& halved_u, bool& halved_v) {
  u = coarser(f.u, halved_u, f.Pu);
  v = coarser(f.v, halved_v, f.Pv);
  if (halved_u || halved_v) return true;
  f.Pu = f.Pv = RowMatrix();
  return false;
}

class TensorMultigrid final : public Preconditioner {
 public:
  TensorMultigrid(std::vector<Level> levels, Eigen::SparseMatrix<double> coarsest)
      : levels_(std::move(levels)), work_(levels_.size()) {
    coarse_.compute(coarsest);
    if (coarse_.info() != Eigen::Success)
      throw std::runtime_error("multigrid: the coarsest operator is not positive definite");
  }

  void apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const override {
    z.resize(r.size());
    cycle(0, r, z);
  }

 private:
  struct Work {
    Eigen::VectorXd residual, coarse_rhs, coarse_x;
    Eigen::MatrixXd half;  // one direction restricted or prolonged (kept: fresh pages cost)
  };

  // x := the V-cycle's approximation of A_l^{-1} b.
  void cycle(size_t l, const Eigen::VectorXd& b, Eigen::VectorXd& x) const {
    if (l + 1 == levels_.size()) {
      x = coarse_.solve(b);
      return;
    }
    const Level& L = levels_[l];
    Work& w = work_[l];
    x.setZero(b.size());
    const int tilings = static_cast<int>(L.u.tilings.size());
    for (int t = 0; t < tilings; ++t)
      for (int c = 0; c < 4; ++c) sweep(L, t, c, b, x, /*x_is_zero=*/t == 0 && c == 0);
    w.residual.resize(b.size());
    const int n = static_cast<int>(b.size());
    if (L.op) {
      L.op->apply_within(x.data(), L.free, w.residual.data());
      w.residual = b - w.residual;
    } else {
#pragma omp parallel for schedule(static)
      for (int d = 0; d < n; ++d) w.residual[d] = b[d] - row_dot(L.A, d, x.data());
    }
    // Restriction (P_v (x) P_u)^T r and prolongation, with vectors as count_u x count_v arrays.
    const Level& C = levels_[l + 1];
    {
      const Eigen::Map<const Eigen::MatrixXd> R(w.residual.data(), L.u.count, L.v.count);
      w.half.resize(C.u.count, L.v.count);
      w.half.noalias() = L.Pu.transpose() * R;
      w.coarse_rhs.resize(C.size());
      Eigen::Map<Eigen::MatrixXd>(w.coarse_rhs.data(), C.u.count, C.v.count).noalias() = w.half * L.Pv;
    }
    cycle(l + 1, w.coarse_rhs, w.coarse_x);
    {
      const Eigen::Map<const Eigen::MatrixXd> X(w.coarse_x.data(), C.u.count, C.v.count);
      w.half.resize(L.u.count, C.v.count);
      w.half.noalias() = L.Pu * X;
      const Eigen::MatrixXd& T = w.half;
      // x(:, j) += sum_k P_v(j, k) T(:, k), fine column by fine column (Eigen's dense times
      // transposed sparse product took 0.11 s of a 0.65 s V-cycle at 4.2M dofs).
      const int nu = L.u.count, nv = L.v.count;
#pragma omp parallel for schedule(static)
      for (int j = 0; j < nv; ++j) {
        double* column = x.data() + long(nu) * j;
        for (RowMatrix::InnerIterator p(L.Pv, j); p; ++p) {
          const double a = p.value(), *t = T.data() + long(nu) * p.col();
          for (int i = 0; i < nu; ++i) column[i] += a * t[i];
        }
      }
    }
    for (int t = tilings - 1; t >= 0; --t)
      for (int c = 3; c >= 0; --c) sweep(L, t, c, b, x);
  }

  // One colour of one tiling: every block (a, c) with a = cu, c = cv mod 2 gets
  // x_B += D^{-1/2} P_B^{-1} D^{-1/2} (b - A x)_B. Such blocks do not couple, so they are done
  // at once, each reading only its own rows.
  // (x_is_zero: the cycle's first colour, whose residual is b.)
  static void sweep(const Level& L, int tiling, int colour, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                    bool x_is_zero = false) {
    const std::vector<Window>& wu = L.u.tilings[tiling];
    const std::vector<Window>& wv = L.v.tilings[tiling];
    const int cu = colour & 1, cv = colour >> 1;
    const int na = (static_cast<int>(wu.size()) - cu + 1) / 2, nb = (static_cast<int>(wv.size()) - cv + 1) / 2;
    const int nu = L.u.count;
#pragma omp parallel for schedule(dynamic)
    for (int k = 0; k < na * nb; ++k) {
      const Window& U = wu[cu + 2 * (k % na)];
      const Window& V = wv[cv + 2 * (k / na)];
      thread_local Eigen::MatrixXd R, T;
      R.resize(U.size, V.size);
      if (x_is_zero) {
        for (int j = 0; j < V.size; ++j)
          for (int i = 0; i < U.size; ++i) {
            const int d = U.begin + i + nu * (V.begin + j);
            R(i, j) = b[d] * L.scale[d];
          }
      } else if (L.op) {  // (A x)_B from the elements that touch the block
        const TensorPoissonOperator::FunctionBox rows{L.free.first_u + U.begin, U.size, L.free.first_v + V.begin, V.size};
        L.op->apply_rows(x.data(), L.free, rows, R.data());
        for (int j = 0; j < V.size; ++j)
          for (int i = 0; i < U.size; ++i) {
            const int d = U.begin + i + nu * (V.begin + j);
            R(i, j) = (b[d] - R(i, j)) * L.scale[d];
          }
      } else {
        for (int j = 0; j < V.size; ++j)
          for (int i = 0; i < U.size; ++i) {
            const int d = U.begin + i + nu * (V.begin + j);
            R(i, j) = (b[d] - row_dot(L.A, d, x.data())) * L.scale[d];
          }
      }
      solve_in_eigenbases(U, V, R, T, L.shift);
      for (int j = 0; j < V.size; ++j)
        for (int i = 0; i < U.size; ++i) {
          const int d = U.begin + i + nu * (V.begin + j);
          x[d] += L.scale[d] * R(i, j);
        }
    }
  }

  std::vector<Level> levels_;
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> coarse_;
  mutable std::vector<Work> work_;
};

// A reaction term, read off the level's A 1 (multigrid_levels::reaction_shift; without it,
// c = 1000 took 126-146 CG iterations at 64^2, p = 2).
double level_reaction_shift(const Level& L) {
  Eigen::VectorXd a1(L.size());
  if (L.op) {
    if (L.op->reaction() == 0) return 0.0;  // (an operator application saved on the default path)
    const Eigen::VectorXd ones = Eigen::VectorXd::Ones(L.size());
    L.op->apply_within(ones.data(), L.free, a1.data());
  } else {
    for (long d = 0; d < L.size(); ++d) a1[d] = L.A.row(d).sum();
  }
  return reaction_shift(a1, L.u, L.v);
}

void set_scale(Level& L, const Eigen::VectorXd& diagonal) {
  L.shift = level_reaction_shift(L);
  L.scale.resize(L.size());
  for (int j = 0; j < L.v.count; ++j)
    for (int i = 0; i < L.u.count; ++i) {
      const long d = i + static_cast<long>(L.u.count) * j;
      const double p = L.u.stiffness_diagonal[i] * L.v.mass_diagonal[j] + L.u.mass_diagonal[i] * L.v.stiffness_diagonal[j] +
                       L.shift * L.u.mass_diagonal[i] * L.v.mass_diagonal[j];
      L.scale[d] = diagonal[d] > 0 && p > 0 ? std::sqrt(p / diagonal[d]) : 1.0;
    }
}

// Q^T A Q for Q the prolongation P (fine x coarse) along direction `dir` of a grid of n0 x n1
// functions (index a + n0 b) and the identity along the other, row by row of the result:
// coarse row r sums P(i, I) A(fine row, (a2, b2)) P(x2, K) over the fine rows of column I of P
// (along dir) and their entries, x2 the entry's index along dir. (The bivariate case of
// multigrid_levels::galerkin_direction, kept apart: the general one took 1.3-1.4 times as long
// here at 1M dofs, p = 2, the same result, one sitting.)
void galerkin_direction_2d(const RowMatrix& A, int n0, int n1, const RowMatrix& P, int dir, RowMatrix& B) {
  const Eigen::SparseMatrix<double> columns = P;
  const int nc = static_cast<int>(P.cols());
  const int m0 = dir == 0 ? nc : n0, m1 = dir == 1 ? nc : n1;
  rows_by_accumulation(static_cast<long>(m0) * m1, B, [&](long r, auto&& add) {
    const int I = static_cast<int>(r % m0), J = static_cast<int>(r / m0);
    for (Eigen::SparseMatrix<double>::InnerIterator p(columns, dir == 0 ? I : J); p; ++p) {
      const int fine_row = dir == 0 ? static_cast<int>(p.row()) + n0 * J : I + n0 * static_cast<int>(p.row());
      for (RowMatrix::InnerIterator a(A, fine_row); a; ++a) {
        const int a2 = static_cast<int>(a.col() % n0), b2 = static_cast<int>(a.col() / n0);
        const double w = p.value() * a.value();
        for (RowMatrix::InnerIterator q(P, dir == 0 ? a2 : b2); q; ++q)
          add(dir == 0 ? q.col() + static_cast<long>(m0) * b2 : a2 + static_cast<long>(m0) * q.col(), w * q.value());
      }
    }
  });
}

// P^T A P with P = P_v (x) P_u = (P_v (x) I)(I (x) P_u): one direction at a time (a direction
// not halved, P the identity, is skipped), each pass reading p + 2 fine rows per coarse row
// where the product with P read (p + 2)^2, each entry going to p + 1 coarse columns where it
// went to (p + 1)^2. (The one-pass product took 3.4 s at 4.2M dofs, p = 2, and 3.0 s at 266k
// dofs, p = 4; Eigen's sparse products 20.6 s at 4.2M.)
void galerkin(const RowMatrix& A, int nu, int nv, const RowMatrix& Pu, const RowMatrix& Pv, bool halved_u, bool halved_v,
              RowMatrix& Ac) {
  if (halved_u && halved_v) {
    RowMatrix B;
    galerkin_direction_2d(A, nu, nv, Pu, 0, B);
    galerkin_direction_2d(B, static_cast<int>(Pu.cols()), nv, Pv, 1, Ac);
  } else if (halved_u) {
    galerkin_direction_2d(A, nu, nv, Pu, 0, Ac);
  } else {
    galerkin_direction_2d(A, nu, nv, Pv, 1, Ac);
  }
}

// The smoothers' windows and scalings of every level but the coarsest (from each level's
// diagonal over its free dofs), the report, and the V-cycle with the coarsest level's factor.
std::unique_ptr<Preconditioner> finish_hierarchy(std::vector<Level> levels, const std::vector<Eigen::VectorXd>& diagonals,
                                                 int block, const TensorMultigridOptions& options,
                                                 TensorMultigridReport* report) {
  for (size_t l = 0; l + 1 < levels.size(); ++l) {
    build_windows(levels[l].u, block, options.tilings);
    build_windows(levels[l].v, block, options.tilings);
    set_scale(levels[l], diagonals[l]);
  }
  if (report) {
    report->free_dofs.clear();
    report->without_matrix = 0;
    for (const Level& L : levels) report->free_dofs.push_back(L.size()), report->without_matrix += L.op != nullptr;
    report->block = block;
  }
  Eigen::SparseMatrix<double> coarsest = levels.back().A;
  levels.back().A = RowMatrix();
  return std::make_unique<TensorMultigrid>(std::move(levels), std::move(coarsest));
}

}  // namespace

std::unique_ptr<Preconditioner> tensor_multigrid(const BSplineBasis1D& space_u, const BSplineBasis1D& space_v,
                                                 const DofLayout& layout, const Eigen::SparseMatrix<double>& lower,
                                                 const SeparableCoefficients& geometry, const NitscheEnds& nitsche,
                                                 const TensorMultigridOptions& options, TensorMultigridReport* report) {
  const int nu = space_u.num_functions(), nv = space_v.num_functions();
  std::vector<int> iu, iv;
  if (!tensor_free_indices(nu, nv, layout, iu, iv) || !space_u.is_open() || !space_v.is_open()) return nullptr;
  // (Reserved: Eigen 3.4's SparseMatrix has no move constructor, so a reallocation would copy
  // every level's matrix.)
  std::vector<Level> levels;
  levels.reserve(64);
  levels.emplace_back();
  Level& fine = levels.back();
  if (!free_range(iu, nu, fine.u) || !free_range(iv, nv, fine.v)) return nullptr;
  const int p = std::max(space_u.degree(), space_v.degree());
  const int block = block_side(options.block, p);
  const auto& side = nitsche.sides;  // bottom, right, top, left
  fine.u.basis = space_u;
  fine.u.mass_weight = geometry.a2;
  fine.u.stiffness_weight = geometry.a1;
  fine.u.nitsche_start = side[3];
  fine.u.nitsche_end = side[1];
  fine.v.basis = space_v;
  fine.v.mass_weight = geometry.b1;
  fine.v.stiffness_weight = geometry.b2;
  fine.v.nitsche_start = side[0];
  fine.v.nitsche_end = side[2];
  fine.u.nitsche_factor = fine.v.nitsche_factor = nitsche.factor;
  whole_from_lower(lower, fine.u.count, fine.v.count, {space_u.degree(), space_v.degree(), 0}, fine.A);
  while (levels.back().size() > options.coarsest_functions && levels.size() < levels.capacity()) {
    Level& f = levels.back();
    bool hu = false, hv = false;
    Direction u, v;
    if (!coarsen(f, u, v, hu, hv)) break;
    levels.emplace_back();
    Level& c = levels.back();
    c.u = std::move(u);
    c.v = std::move(v);
    galerkin(f.A, f.u.count, f.v.count, f.Pu, f.Pv, hu, hv, c.A);
  }
  std::vector<Eigen::VectorXd> diagonals;
  for (const Level& L : levels) diagonals.push_back(L.A.diagonal());
  return finish_hierarchy(std::move(levels), diagonals, block, options, report);
}

std::unique_ptr<Preconditioner> tensor_multigrid(std::shared_ptr<const TensorPoissonOperator> op, const DofLayout& layout,
                                                 const Eigen::VectorXd& free_diagonal, const SeparableCoefficients& geometry,
                                                 const TensorMultigridOptions& options, TensorMultigridReport* report) {
  const BSplineBasis1D &space_u = op->space_u(), &space_v = op->space_v();
  const int nu = space_u.num_functions(), nv = space_v.num_functions();
  std::vector<int> iu, iv;
  if (!tensor_free_indices(nu, nv, layout, iu, iv) || !space_u.is_open() || !space_v.is_open()) return nullptr;
  std::vector<Level> levels;
  levels.reserve(64);
  std::vector<Eigen::VectorXd> diagonals;  // per level, over its free functions
  levels.emplace_back();
  Level& fine = levels.back();
  if (!free_range(iu, nu, fine.u) || !free_range(iv, nv, fine.v)) return nullptr;
  const int p = std::max(space_u.degree(), space_v.degree());
  const int block = block_side(options.block, p);
  fine.u.basis = space_u;
  fine.u.mass_weight = geometry.a2;
  fine.u.stiffness_weight = geometry.a1;
  fine.v.basis = space_v;
  fine.v.mass_weight = geometry.b1;
  fine.v.stiffness_weight = geometry.b2;
  auto box = [](const Level& L) {
    return TensorPoissonOperator::FunctionBox{L.u.first, L.u.count, L.v.first, L.v.count};
  };
  fine.op = std::move(op);
  fine.free = box(fine);
  diagonals.push_back(free_diagonal);
  // Rediscretized levels while the geometry lives on the coarser elements; from the first that
  // cannot be, the matrix of the last operator (by probing) and Galerkin products below it.
  while (levels.back().size() > options.coarsest_functions && levels.size() < levels.capacity()) {
    Level& f = levels.back();
    bool hu = false, hv = false;
    Direction u, v;
    if (!coarsen(f, u, v, hu, hv)) break;
    std::shared_ptr<const TensorPoissonOperator> coarse_op;
    if (f.op) {
      coarse_op = rediscretized_operator(*f.op, hu, hv);
      // On the finest level that would mean assembling the matrix the caller chose not to
      // store: the multigrid without a matrix does not apply.
      if (!coarse_op && levels.size() == 1) return nullptr;
      if (!coarse_op) {
        f.A = matrix_by_probing(*f.op, f.free);
        f.op = nullptr;
      }
    }
    levels.emplace_back();
    Level& c = levels.back();
    Level& f2 = levels[levels.size() - 2];
    c.u = std::move(u);
    c.v = std::move(v);
    if (coarse_op) {
      c.op = std::move(coarse_op);
      c.free = box(c);
      const Eigen::VectorXd all = c.op->diagonal();
      Eigen::VectorXd d(c.size());
      for (int j = 0; j < c.v.count; ++j)
        for (int i = 0; i < c.u.count; ++i) d[i + long(c.u.count) * j] = all[(c.u.first + i) + long(c.u.basis.num_functions()) * (c.v.first + j)];
      diagonals.push_back(std::move(d));
    } else {
      galerkin(f2.A, f2.u.count, f2.v.count, f2.Pu, f2.Pv, hu, hv, c.A);
      diagonals.push_back(c.A.diagonal());
    }
  }
  // A fine level that does not coarsen (odd element counts) would be factored whole.
  if (levels.size() == 1 && levels.back().size() > options.coarsest_functions) return nullptr;
  if (levels.back().op) {
    levels.back().A = matrix_by_probing(*levels.back().op, levels.back().free);
    levels.back().op = nullptr;
  }
  return finish_hierarchy(std::move(levels), diagonals, block, options, report);
}

}  // namespace knotwork
