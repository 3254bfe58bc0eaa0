#include "solver/tensor_multigrid_3d.hpp"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "solver/sparsity.hpp"
#include "solver/tensor_multigrid_levels.hpp"

namespace knotwork {

double tensor_multigrid_3d_bytes(double functions, const std::array<int, 3>& degree, bool with_matrix) {
  if (!with_matrix) return functions * 8 * 7 * 8 / 7;
  double coupling = 1;
  for (int p : degree) coupling *= 2 * p + 1;
  return (functions * coupling * 12 + functions * 8 * 6) * 8 / 7;
}

namespace {

using namespace multigrid_levels;

// The largest coarsest level factored (a 3D grid of about 37^3).
constexpr long kCoarsestLimit = 50000;

struct Level {
  std::array<Direction, 3> d;
  RowMatrix A;            // the whole matrix over this level's free dofs, a + n_u (b + n_v c)
  // Or, without a matrix, the level's operator and its free functions (a box of them).
  std::shared_ptr<const AffineVolumeOperator> op;
  AffineVolumeOperator::FunctionBox free;
  Eigen::VectorXd scale;  // D^{-1/2}, D = diag(A) / diag(P)
  double shift = 0;       // P's reaction term: shift M_u (x) M_v (x) M_w (reaction_shift)
  std::array<RowMatrix, 3> P;  // from the next coarser level, per direction (the identity where not halved)
  std::array<int, 3> counts() const { return {d[0].count, d[1].count, d[2].count}; }
  long size() const { return static_cast<long>(d[0].count) * d[1].count * d[2].count; }
};

// y := x contracted with P along mode `mode` of an array of dimensions `in` (first index
// fastest): transpose, y_I = sum_i P(i, I) x_i (restriction); else y_i = sum_I P(i, I) x_I.
void along(const RowMatrix& P, bool transpose, const std::array<int, 3>& in, int mode, const double* x, double* y) {
  long inner = 1, outer = 1;
  for (int k = 0; k < mode; ++k) inner *= in[k];
  for (int k = mode + 1; k < 3; ++k) outer *= in[k];
  const long n_in = in[mode], n_out = transpose ? P.cols() : P.rows();
  const long chunk = std::min<long>(inner, 512), chunks = (inner + chunk - 1) / chunk;
#pragma omp parallel for schedule(static)
  for (long t = 0; t < outer * chunks; ++t) {
    const long o = t / chunks, c0 = (t % chunks) * chunk, c1 = std::min(inner, c0 + chunk);
    const double* xo = x + o * n_in * inner;
    double* yo = y + o * n_out * inner;
    for (long j = 0; j < n_out; ++j) std::fill(yo + j * inner + c0, yo + j * inner + c1, 0.0);
    for (long i = 0; i < P.rows(); ++i)
      for (RowMatrix::InnerIterator p(P, i); p; ++p) {
        const double v = p.value();
        const double* src = xo + (transpose ? i : p.col()) * inner;
        double* dst = yo + (transpose ? p.col() : i) * inner;
        for (long k = c0; k < c1; ++k) dst[k] += v * src[k];
      }
  }
}

class TensorMultigrid3d final : public Preconditioner {
 public:
  TensorMultigrid3d(std::vector<Level> levels, Eigen::SparseMatrix<double> coarsest)
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
    Eigen::VectorXd residual, coarse_rhs, coarse_x, a, b;
  };

  void cycle(size_t l, const Eigen::VectorXd& rhs, Eigen::VectorXd& x) const {
    if (l + 1 == levels_.size()) {
      x = coarse_.solve(rhs);
      return;
    }
    const Level& L = levels_[l];
    const Level& C = levels_[l + 1];
    Work& w = work_[l];
    x.setZero(rhs.size());
    const int tilings = static_cast<int>(L.d[0].tilings.size());
    for (int t = 0; t < tilings; ++t)
      for (int c = 0; c < 8; ++c) sweep(L, t, c, rhs, x, /*x_is_zero=*/t == 0 && c == 0);
    const long n = L.size();
    w.residual.resize(n);
    if (L.op) {
      L.op->apply_within(x.data(), L.free, w.residual.data());
#pragma omp parallel for schedule(static)
      for (long i = 0; i < n; ++i) w.residual[i] = rhs[i] - w.residual[i];
    } else {
#pragma omp parallel for schedule(static)
      for (long i = 0; i < n; ++i) w.residual[i] = rhs[i] - row_dot(L.A, i, x.data());
    }
    // Restriction (P_w (x) P_v (x) P_u)^T r, one mode at a time.
    const std::array<int, 3> f = L.counts(), c = C.counts();
    w.a.resize(long(c[0]) * f[1] * f[2]);
    w.b.resize(long(c[0]) * c[1] * f[2]);
    w.coarse_rhs.resize(C.size());
    along(L.P[0], true, f, 0, w.residual.data(), w.a.data());
    along(L.P[1], true, {c[0], f[1], f[2]}, 1, w.a.data(), w.b.data());
    along(L.P[2], true, {c[0], c[1], f[2]}, 2, w.b.data(), w.coarse_rhs.data());
    cycle(l + 1, w.coarse_rhs, w.coarse_x);
    along(L.P[2], false, c, 2, w.coarse_x.data(), w.b.data());
    along(L.P[1], false, {c[0], c[1], f[2]}, 1, w.b.data(), w.a.data());
    along(L.P[0], false, {c[0], f[1], f[2]}, 0, w.a.data(), w.residual.data());
    x += w.residual;
    for (int t = tilings - 1; t >= 0; --t)
      for (int c = 7; c >= 0; --c) sweep(L, t, c, rhs, x);
  }

  // One colour of one tiling: every block whose window indices have the colour's parities gets
  // x_B += D^{-1/2} P_B^{-1} D^{-1/2} (b - A x)_B. Such blocks do not couple (windows are longer
  // than the degree), so they are done at once, each reading only its own rows.
  static void sweep(const Level& L, int tiling, int colour, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                    bool x_is_zero = false) {
    const std::vector<Window>& wu = L.d[0].tilings[tiling];
    const std::vector<Window>& wv = L.d[1].tilings[tiling];
    const std::vector<Window>& ww = L.d[2].tilings[tiling];
    const int cu = colour & 1, cv = (colour >> 1) & 1, cw = colour >> 2;
    const int na = (static_cast<int>(wu.size()) - cu + 1) / 2, nb = (static_cast<int>(wv.size()) - cv + 1) / 2,
              nc = (static_cast<int>(ww.size()) - cw + 1) / 2;
    const long nu = L.d[0].count, nv = L.d[1].count;
#pragma omp parallel for schedule(dynamic)
    for (int k = 0; k < na * nb * nc; ++k) {
      const Window& U = wu[cu + 2 * (k % na)];
      const Window& V = wv[cv + 2 * ((k / na) % nb)];
      const Window& W = ww[cw + 2 * (k / (na * nb))];
      const int su = U.size, sv = V.size, sw = W.size;
      const long block = long(su) * sv * sw;
      thread_local Eigen::VectorXd R, T;
      R.resize(block);
      T.resize(block);
      auto dof = [&](int i, int j, int l) { return U.begin + i + nu * (V.begin + j + nv * (W.begin + l)); };
      if (L.op && !x_is_zero) {  // (A x)_B by mode products over the block's reach
        const AffineVolumeOperator::FunctionBox rows{
            {L.free.first[0] + U.begin, L.free.first[1] + V.begin, L.free.first[2] + W.begin}, {su, sv, sw}};
        L.op->apply_box(x.data(), L.free, rows, R.data());
      }
      for (int l = 0, at = 0; l < sw; ++l)
        for (int j = 0; j < sv; ++j)
          for (int i = 0; i < su; ++i, ++at) {
            const long d = dof(i, j, l);
            R[at] = (x_is_zero ? b[d] : L.op ? b[d] - R[at] : b[d] - row_dot(L.A, d, x.data())) * L.scale[d];
          }
      solve_in_eigenbases(U, V, W, R, T, L.shift);
      for (int l = 0, at = 0; l < sw; ++l)
        for (int j = 0; j < sv; ++j)
          for (int i = 0; i < su; ++i, ++at) {
            const long d = dof(i, j, l);
            x[d] += L.scale[d] * R[at];
          }
    }
  }

  std::vector<Level> levels_;
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> coarse_;
  mutable std::vector<Work> work_;
};

// A reaction term, read off the level's A 1 (multigrid_levels::reaction_shift; without it,
// c = 1000 took 81 CG iterations on the cube at 16^3, p = 2, and on the thick quarter annulus
// CG did not converge in 1 000).
double level_reaction_shift(const Level& L) {
  Eigen::VectorXd a1(L.size());
  if (L.op) {
    if (L.op->reaction() == 0) return 0.0;  // (an operator application saved on the default path)
    const Eigen::VectorXd ones = Eigen::VectorXd::Ones(L.size());
    L.op->apply_within(ones.data(), L.free, a1.data());
  } else {
    for (long d = 0; d < L.size(); ++d) a1[d] = L.A.row(d).sum();
  }
  return reaction_shift(a1, L.d[0], L.d[1], &L.d[2]);
}

void set_scale(Level& L, const Eigen::VectorXd& diagonal) {
  L.shift = level_reaction_shift(L);
  L.scale.resize(L.size());
  const Direction &u = L.d[0], &v = L.d[1], &w = L.d[2];
  long at = 0;
  for (int c = 0; c < w.count; ++c)
    for (int b = 0; b < v.count; ++b)
      for (int a = 0; a < u.count; ++a, ++at) {
        const double p = u.stiffness_diagonal[a] * v.mass_diagonal[b] * w.mass_diagonal[c] +
                         u.mass_diagonal[a] * v.stiffness_diagonal[b] * w.mass_diagonal[c] +
                         u.mass_diagonal[a] * v.mass_diagonal[b] * w.stiffness_diagonal[c] +
                         L.shift * u.mass_diagonal[a] * v.mass_diagonal[b] * w.mass_diagonal[c];
        L.scale[at] = diagonal[at] > 0 && p > 0 ? std::sqrt(p / diagonal[at]) : 1.0;
      }
}

void refuse_large_coarsest(long size, const TensorMultigridOptions& options) {
  if (size > kCoarsestLimit)
    throw std::invalid_argument("\"multigrid\" halves the element count of each direction down to at most " +
                                std::to_string(options.coarsest_functions) + " unknowns, but it stops at " +
                                std::to_string(size) +
                                " (an odd number of elements in every direction); use element counts with more factors of 2, or "
                                "\"fast_diagonalization\"");
}

// The next coarser level's directions, and the finest level's prolongations to it; false (and
// no prolongations) when no direction halves. `levels` has room (reserved: no reallocation).
bool add_coarser_level(std::vector<Level>& levels, std::array<bool, 3>& halved) {
  Level& f = levels.back();
  std::array<Direction, 3> d;
  for (int k = 0; k < 3; ++k) d[k] = coarser(f.d[k], halved[k], f.P[k]);
  if (!halved[0] && !halved[1] && !halved[2]) {
    f.P = {};
    return false;
  }
  levels.emplace_back();
  levels.back().d = std::move(d);
  return true;
}

// The finest level's directions (bases, free ranges, the geometry's weights, Nitsche's ends);
// false when the free dofs are not a tensor product of free ranges or a knot vector is not open.
bool fine_level(const std::array<BSplineBasis1D, 3>& spaces, const DofLayout& layout, const SeparableVolumeCoefficients& geometry,
                const std::array<bool, 6>& nitsche, double nitsche_factor, Level& fine) {
  const std::array<int, 3> n{spaces[0].num_functions(), spaces[1].num_functions(), spaces[2].num_functions()};
  std::array<std::vector<int>, 3> free;
  if (!tensor_free_indices_3d(n, layout, free)) return false;
  for (int k = 0; k < 3; ++k) {
    Direction& d = fine.d[k];
    if (!spaces[k].is_open() || !free_range(free[k], n[k], d)) return false;
    d.basis = spaces[k];
    d.mass_weight = geometry.mu[k];
    d.stiffness_weight = geometry.tau[k];
    d.nitsche_start = nitsche[2 * k];
    d.nitsche_end = nitsche[2 * k + 1];
    d.nitsche_factor = nitsche_factor;
  }
  return true;
}

// The smoothers' windows and scalings (from each level's diagonal over its free dofs), the
// report, and the V-cycle with the coarsest level's factor. The coarsest level is factored by
// sparse Cholesky, whose fill grows like N^(4/3) on a volume's grid: an odd element count that
// stops the halving early is refused, not factored.
std::unique_ptr<Preconditioner> finish_hierarchy(std::vector<Level> levels, const std::vector<Eigen::VectorXd>& diagonals,
                                                 Eigen::SparseMatrix<double> coarsest, int block,
                                                 const TensorMultigridOptions& options, TensorMultigridReport* report) {
  refuse_large_coarsest(levels.back().size(), options);
  for (size_t l = 0; l + 1 < levels.size(); ++l) {
    for (Direction& d : levels[l].d) build_windows(d, block, options.tilings);
    set_scale(levels[l], diagonals[l]);
  }
  if (report) {
    report->free_dofs.clear();
    report->without_matrix = 0;
    for (const Level& L : levels) report->free_dofs.push_back(L.size()), report->without_matrix += L.op != nullptr;
    report->block = block;
  }
  return std::make_unique<TensorMultigrid3d>(std::move(levels), std::move(coarsest));
}

}  // namespace

std::unique_ptr<Preconditioner> tensor_multigrid_3d(const std::array<BSplineBasis1D, 3>& spaces, const DofLayout& layout,
                                                    const Eigen::SparseMatrix<double>& lower,
                                                    const SeparableVolumeCoefficients& geometry,
                                                    const std::array<bool, 6>& nitsche, double nitsche_factor,
                                                    const TensorMultigridOptions& options, TensorMultigridReport* report) {
  std::vector<Level> levels;
  levels.reserve(64);  // (Eigen 3.4's SparseMatrix has no move constructor: no reallocation)
  levels.emplace_back();
  if (!fine_level(spaces, layout, geometry, nitsche, nitsche_factor, levels[0])) return nullptr;
  int p = 0;
  for (const BSplineBasis1D& b : spaces) p = std::max(p, b.degree());
  const int block = block_side(options.block, p);
  whole_from_lower(lower, levels[0].d[0].count, levels[0].d[1].count,
                   {spaces[0].degree(), spaces[1].degree(), spaces[2].degree()}, levels[0].A);
  std::array<bool, 3> halved{};
  while (levels.back().size() > options.coarsest_functions && levels.size() < levels.capacity() &&
         add_coarser_level(levels, halved)) {
    Level& c = levels.back();
    const Level& fine = levels[levels.size() - 2];
    // P^T A P one direction at a time (not halved: the identity, skipped), through two buffers.
    std::array<RowMatrix, 2> buffer;
    const RowMatrix* in = &fine.A;
    int out = 0;
    std::array<int, 3> dims = fine.counts();
    for (int k = 0; k < 3; ++k) {
      if (!halved[k]) continue;
      galerkin_direction(*in, dims, fine.P[k], k, buffer[out]);
      dims[k] = c.d[k].count;
      in = &buffer[out];
      out = 1 - out;
    }
    c.A.swap(buffer[1 - out]);
  }
  std::vector<Eigen::VectorXd> diagonals;
  for (const Level& L : levels) diagonals.push_back(L.A.diagonal());
  Eigen::SparseMatrix<double> coarsest = levels.back().A;
  levels.back().A = RowMatrix();
  return finish_hierarchy(std::move(levels), diagonals, std::move(coarsest), block, options, report);
}

std::unique_ptr<Preconditioner> tensor_multigrid_3d(std::shared_ptr<const AffineVolumeOperator> op, const DofLayout& layout,
                                                    const Eigen::VectorXd& free_diagonal,
                                                    const SeparableVolumeCoefficients& geometry,
                                                    const TensorMultigridOptions& options, TensorMultigridReport* report) {
  const std::array<BSplineBasis1D, 3>& spaces = op->spaces();
  std::vector<Level> levels;
  levels.reserve(64);
  levels.emplace_back();
  if (!fine_level(spaces, layout, geometry, {}, 2, levels[0])) return nullptr;
  int p = 0;
  for (const BSplineBasis1D& b : spaces) p = std::max(p, b.degree());
  const int block = block_side(options.block, p);
  const auto box = [](const Level& L) {
    AffineVolumeOperator::FunctionBox f;
    for (int k = 0; k < 3; ++k) f.first[k] = L.d[k].first, f.count[k] = L.d[k].count;
    return f;
  };
  levels[0].op = std::move(op);
  levels[0].free = box(levels[0]);
  std::vector<Eigen::VectorXd> diagonals{free_diagonal};
  // Each coarser level: the operator on the halved spaces (on an affine map, the Galerkin one).
  std::array<bool, 3> halved{};
  while (levels.back().size() > options.coarsest_functions && levels.size() < levels.capacity() &&
         add_coarser_level(levels, halved)) {
    Level& c = levels.back();
    const Level& fine = levels[levels.size() - 2];
    c.op = fine.op->on_spaces({c.d[0].basis, c.d[1].basis, c.d[2].basis});
    c.free = box(c);
    const Eigen::VectorXd all = c.op->diagonal();
    Eigen::VectorXd diagonal(c.size());
    const std::array<int, 3> n{c.d[0].basis.num_functions(), c.d[1].basis.num_functions(), c.d[2].basis.num_functions()};
    long at = 0;
    for (int k = 0; k < c.free.count[2]; ++k)
      for (int j = 0; j < c.free.count[1]; ++j)
        for (int i = 0; i < c.free.count[0]; ++i)
          diagonal[at++] = all[(c.free.first[0] + i) + long(n[0]) * ((c.free.first[1] + j) + long(n[1]) * (c.free.first[2] + k))];
    diagonals.push_back(std::move(diagonal));
  }
  // The coarsest level's matrix, written by its operator over its free box.
  Level& last = levels.back();
  refuse_large_coarsest(last.size(), options);
  const std::array<int, 3> n{last.d[0].basis.num_functions(), last.d[1].basis.num_functions(), last.d[2].basis.num_functions()};
  std::vector<bool> fixed(long(n[0]) * n[1] * n[2], true);
  for (int k = 0; k < last.free.count[2]; ++k)
    for (int j = 0; j < last.free.count[1]; ++j)
      for (int i = 0; i < last.free.count[0]; ++i)
        fixed[(last.free.first[0] + i) + long(n[0]) * ((last.free.first[1] + j) + long(n[1]) * (last.free.first[2] + k))] = false;
  Eigen::SparseMatrix<double> coarsest = last.op->lower_matrix(make_dof_layout(int(fixed.size()), fixed));
  last.op = nullptr;
  return finish_hierarchy(std::move(levels), diagonals, std::move(coarsest), block, options, report);
}

}  // namespace knotwork
