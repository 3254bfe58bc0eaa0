#include "solver/patchwise_multigrid.hpp"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "solver/tensor_multigrid_levels.hpp"

namespace knotwork {

// Knot insertion computes its coefficients through Bezier extraction: a coefficient that is
// zero in exact arithmetic may come out as rounding (below 1e-15, the coefficients lie in
// [0, 1]). Below this it is zero: it must not make an interior function fixed.
constexpr double kZeroCoefficient = 1e-12;

void link_coarser(PatchwiseLevel& fine, PatchwiseLevel& coarse) {
  if (fine.patches.size() != coarse.patches.size())
    throw std::invalid_argument("multigrid: a coarser level has another number of patches");
  int coarse_functions = 0;
  for (const MultigridPatch& c : coarse.patches)
    for (int f : c.function) coarse_functions = std::max(coarse_functions, f + 1);
  const int fine_functions = static_cast<int>(fine.layout.dof.size());
  std::vector<char> done(fine_functions, 0);
  std::vector<char> fixed(coarse_functions, 0);
  struct Entry {
    int fine, coarse;
    double value;
  };
  std::vector<Entry> entries;
  for (size_t k = 0; k < fine.patches.size(); ++k) {
    const MultigridPatch& F = fine.patches[k];
    const MultigridPatch& C = coarse.patches[k];
    using RowMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor>;
    const RowMatrix Tu = refinement_matrix(C.u, F.u), Tv = refinement_matrix(C.v, F.v);
    const int nfu = F.u.num_functions(), ncu = C.u.num_functions();
    if (F.function.size() != static_cast<size_t>(nfu) * F.v.num_functions() ||
        C.function.size() != static_cast<size_t>(ncu) * C.v.num_functions())
      throw std::invalid_argument("multigrid: a patch's function numbering does not match its bases");
    for (int j = 0; j < Tv.rows(); ++j)
      for (int i = 0; i < nfu; ++i) {
        const int f = F.function[i + nfu * j];
        // A shared function's coefficients are the same from every patch that holds it.
        if (done[f]) continue;
        done[f] = 1;
        const bool fine_fixed = fine.layout.dof[f] < 0;
        for (RowMatrix::InnerIterator b(Tv, j); b; ++b)
          for (RowMatrix::InnerIterator a(Tu, i); a; ++a) {
            const double value = a.value() * b.value();
            if (std::abs(value) < kZeroCoefficient) continue;
            const int c = C.function[a.col() + ncu * b.col()];
            if (fine_fixed)
              fixed[c] = 1;
            else
              entries.push_back({fine.layout.dof[f], c, value});
          }
      }
  }
  coarse.layout = make_dof_layout(coarse_functions, std::vector<bool>(fixed.begin(), fixed.end()));
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(entries.size());
  for (const Entry& e : entries)
    if (const int c = coarse.layout.dof[e.coarse]; c >= 0) triplets.emplace_back(e.fine, c, e.value);
  fine.prolongation.resize(fine.layout.num_free(), coarse.layout.num_free());
  fine.prolongation.setFromTriplets(triplets.begin(), triplets.end());
}

namespace {

// Weights per element of `fine` carried to the elements of `coarse` (whose breakpoints are
// among fine's): each the geometric mean of those of the fine elements inside it.
std::vector<double> merged_weights(const BSplineBasis1D& fine, const BSplineBasis1D& coarse, const std::vector<double>& w) {
  if (w.empty()) return {};
  const std::vector<double> f = fine.breakpoints(), c = coarse.breakpoints();
  std::vector<double> log_sum(c.size() - 1, 0.0);
  std::vector<int> count(c.size() - 1, 0);
  for (size_t e = 0; e + 1 < f.size(); ++e) {
    const double middle = 0.5 * (f[e] + f[e + 1]);
    const size_t k = std::min<size_t>(std::upper_bound(c.begin(), c.end(), middle) - c.begin() - 1, c.size() - 2);
    log_sum[k] += std::log(w[e]);
    ++count[k];
  }
  std::vector<double> out(log_sum.size());
  for (size_t k = 0; k < out.size(); ++k) out[k] = std::exp(log_sum[k] / std::max(count[k], 1));
  return out;
}

}  // namespace

SeparableCoefficients coarser_fit(const MultigridPatch& fine, const BSplineBasis1D& coarse_u, const BSplineBasis1D& coarse_v) {
  const SeparableCoefficients& g = fine.geometry;
  return {merged_weights(fine.u, coarse_u, g.a1), merged_weights(fine.v, coarse_v, g.b1),
          merged_weights(fine.u, coarse_u, g.a2), merged_weights(fine.v, coarse_v, g.b2)};
}

namespace {

using namespace multigrid_levels;

// A patch's interior functions on one level: a box of its univariate indices.
struct PatchBox {
  Direction u, v;
  std::vector<int> dof;  // a + u.count b -> the level's free dof
  Eigen::VectorXd scale;  // D^{-1/2}, D = diag(A) / diag(the separable operator)
};

struct Block {
  int patch, window_u, window_v;
};

struct Level {
  RowMatrix A;  // the whole matrix over the level's free dofs
  std::vector<PatchBox> boxes;
  std::vector<std::array<std::vector<Block>, 4>> blocks;  // per tiling, per colour
  std::vector<int> strip;                                  // the free dofs the strip solves
  std::unique_ptr<Eigen::SimplicialLLT<Eigen::SparseMatrix<double>>> strip_factor;
  RowMatrix P;  // from the next coarser level
};

// The box of patch `k`'s interior functions (box.dof empty when it has none), its strip
// functions marked in `in_strip`; false when they are not a box. shared[f]: how many patches hold function f.
bool make_box(const PatchwiseLevel& level, size_t k, const std::vector<int>& shared, int layers, PatchBox& box,
              std::vector<char>& in_strip) {
  const MultigridPatch& patch = level.patches[k];
  const int nu = patch.u.num_functions(), nv = patch.v.num_functions();
  auto function = [&](int i, int j) { return patch.function[i + nu * j]; };
  auto own = [&](int i, int j) {
    const int f = function(i, j);
    return level.layout.dof[f] >= 0 && shared[f] == 1;
  };
  // Side s (bottom, right, top, left): whether its functions are out of the box (fixed or on
  // an interface), and whether it is an interface. Judged on the side's functions off the
  // corners, which belong to the neighbouring sides too.
  std::array<bool, 4> out{}, interface{};
  for (int s = 0; s < 4; ++s) {
    const bool along_u = s == 0 || s == 2;
    const int n = along_u ? nu : nv;
    for (int t = 1; t + 1 < n; ++t) {
      const int i = along_u ? t : (s == 1 ? nu - 1 : 0), j = along_u ? (s == 0 ? 0 : nv - 1) : t;
      if (!own(i, j)) out[s] = true;
      if (shared[function(i, j)] > 1) interface[s] = true;
    }
  }
  const int iu0 = out[3], iu1 = nu - 1 - out[1], iv0 = out[0], iv1 = nv - 1 - out[2];
  if (iu1 < iu0 || iv1 < iv0) return true;  // none (a patch one function wide between interfaces)
  for (int j = iv0; j <= iv1; ++j)
    for (int i = iu0; i <= iu1; ++i)
      if (!own(i, j)) return false;
  box.u.basis = patch.u;
  box.u.first = iu0;
  box.u.count = iu1 - iu0 + 1;
  box.u.fixed_at_end = nu - 1 - iu1;
  box.u.mass_weight = patch.geometry.a2;
  box.u.stiffness_weight = patch.geometry.a1;
  box.u.nitsche_start = patch.nitsche.sides[3];
  box.u.nitsche_end = patch.nitsche.sides[1];
  box.v.basis = patch.v;
  box.v.first = iv0;
  box.v.count = iv1 - iv0 + 1;
  box.v.fixed_at_end = nv - 1 - iv1;
  box.v.mass_weight = patch.geometry.b1;
  box.v.stiffness_weight = patch.geometry.b2;
  box.v.nitsche_start = patch.nitsche.sides[0];
  box.v.nitsche_end = patch.nitsche.sides[2];
  box.u.nitsche_factor = box.v.nitsche_factor = patch.nitsche.factor;
  box.dof.resize(static_cast<size_t>(box.u.count) * box.v.count);
  for (int b = 0; b < box.v.count; ++b)
    for (int a = 0; a < box.u.count; ++a) {
      const int d = level.layout.dof[function(iu0 + a, iv0 + b)];
      box.dof[a + box.u.count * b] = d;
      const bool near = (interface[3] && a < layers) || (interface[1] && a >= box.u.count - layers) ||
                        (interface[0] && b < layers) || (interface[2] && b >= box.v.count - layers);
      if (near) in_strip[d] = 1;
    }
  return true;
}

// B = P^T A P, in two threaded sparse products (A P, then P^T (A P)), each row by row.
void galerkin(const RowMatrix& A, const RowMatrix& P, RowMatrix& B) {
  RowMatrix AP;
  rows_by_accumulation(
      A.rows(), AP,
      [&](long r, auto&& add) {
        for (RowMatrix::InnerIterator a(A, r); a; ++a)
          for (RowMatrix::InnerIterator p(P, a.col()); p; ++p) add(p.col(), a.value() * p.value());
      },
      P.cols());
  const RowMatrix Pt = P.transpose();
  rows_by_accumulation(Pt.rows(), B, [&](long r, auto&& add) {
    for (RowMatrix::InnerIterator p(Pt, r); p; ++p)
      for (RowMatrix::InnerIterator a(AP, p.col()); a; ++a) add(a.col(), p.value() * a.value());
  });
}

class PatchwiseMultigrid final : public Preconditioner {
 public:
  PatchwiseMultigrid(std::vector<Level> levels, const Eigen::SparseMatrix<double>& coarsest)
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
    Eigen::VectorXd residual, coarse_rhs, coarse_x, strip_residual;
  };

  void cycle(size_t l, const Eigen::VectorXd& b, Eigen::VectorXd& x) const {
    if (l + 1 == levels_.size()) {
      x = coarse_.solve(b);
      return;
    }
    const Level& L = levels_[l];
    Work& w = work_[l];
    x.setZero(b.size());
    const int tilings = static_cast<int>(L.blocks.size());
    for (int t = 0; t < tilings; ++t)
      for (int c = 0; c < 4; ++c) sweep(L, L.blocks[t][c], b, x, /*x_is_zero=*/t == 0 && c == 0);
    solve_strip(L, b, x, w);
    const int n = static_cast<int>(b.size());
    w.residual.resize(n);
#pragma omp parallel for schedule(static)
    for (int d = 0; d < n; ++d) w.residual[d] = b[d] - row_dot(L.A, d, x.data());
    w.coarse_rhs.noalias() = L.P.transpose() * w.residual;
    cycle(l + 1, w.coarse_rhs, w.coarse_x);
#pragma omp parallel for schedule(static)
    for (int d = 0; d < n; ++d) x[d] += row_dot(L.P, d, w.coarse_x.data());
    solve_strip(L, b, x, w);
    for (int t = tilings - 1; t >= 0; --t)
      for (int c = 3; c >= 0; --c) sweep(L, L.blocks[t][c], b, x);
  }

  // x_S += A_SS^{-1} (b - A x)_S on the strip S.
  static void solve_strip(const Level& L, const Eigen::VectorXd& b, Eigen::VectorXd& x, Work& w) {
    if (L.strip.empty()) return;
    const int n = static_cast<int>(L.strip.size());
    w.strip_residual.resize(n);
    for (int k = 0; k < n; ++k) w.strip_residual[k] = b[L.strip[k]] - row_dot(L.A, L.strip[k], x.data());
    const Eigen::VectorXd y = L.strip_factor->solve(w.strip_residual);
    for (int k = 0; k < n; ++k) x[L.strip[k]] += y[k];
  }

  // One colour of one tiling over every patch: x_B += D^{-1/2} P_B^{-1} D^{-1/2} (b - A x)_B.
  static void sweep(const Level& L, const std::vector<Block>& blocks, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                    bool x_is_zero = false) {
    const int count = static_cast<int>(blocks.size());
#pragma omp parallel for schedule(dynamic)
    for (int k = 0; k < count; ++k) {
      const PatchBox& box = L.boxes[blocks[k].patch];
      const Window& U = *window_u(box, blocks[k]);
      const Window& V = *window_v(box, blocks[k]);
      thread_local Eigen::MatrixXd R, T;
      R.resize(U.size, V.size);
      const int nu = box.u.count;
      for (int j = 0; j < V.size; ++j)
        for (int i = 0; i < U.size; ++i) {
          const long a = U.begin + i + static_cast<long>(nu) * (V.begin + j);
          const int d = box.dof[a];
          R(i, j) = (x_is_zero ? b[d] : b[d] - row_dot(L.A, d, x.data())) * box.scale[a];
        }
      solve_in_eigenbases(U, V, R, T);
      for (int j = 0; j < V.size; ++j)
        for (int i = 0; i < U.size; ++i) {
          const long a = U.begin + i + static_cast<long>(nu) * (V.begin + j);
          x[box.dof[a]] += box.scale[a] * R(i, j);
        }
    }
  }

  // A block's windows: window_u counts the windows of all tilings of the box's u direction in
  // order (tiling 0's, then tiling 1's), and likewise window_v.
  static const Window* window_u(const PatchBox& box, const Block& b) { return nth_window(box.u, b.window_u); }
  static const Window* window_v(const PatchBox& box, const Block& b) { return nth_window(box.v, b.window_v); }
  static const Window* nth_window(const Direction& d, int n) {
    for (const std::vector<Window>& t : d.tilings) {
      if (n < static_cast<int>(t.size())) return &t[n];
      n -= static_cast<int>(t.size());
    }
    throw std::logic_error("multigrid: a block's window is out of range");
  }

  std::vector<Level> levels_;
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> coarse_;
  mutable std::vector<Work> work_;
};

}  // namespace

std::unique_ptr<Preconditioner> patchwise_multigrid(std::vector<PatchwiseLevel> levels,
                                                    const Eigen::SparseMatrix<double>& lower,
                                                    const PatchwiseMultigridOptions& options,
                                                    PatchwiseMultigridReport* report) {
  if (levels.empty()) throw std::invalid_argument("multigrid: no level");
  int p = 1;
  for (const MultigridPatch& patch : levels.front().patches) p = std::max({p, patch.u.degree(), patch.v.degree()});
  const int block = block_side(options.block, p);
  const int layers = options.strip_layers >= 0 ? options.strip_layers : p;
  std::vector<Level> built(levels.size());
  built[0].A = lower.selfadjointView<Eigen::Lower>();
  if (report) *report = PatchwiseMultigridReport{{}, {}, block};
  for (size_t l = 0; l < levels.size(); ++l) {
    const PatchwiseLevel& level = levels[l];
    Level& L = built[l];
    if (L.A.rows() != level.layout.num_free()) throw std::invalid_argument("multigrid: the matrix does not match the level");
    if (report) report->free_dofs.push_back(level.layout.num_free());
    if (l + 1 == levels.size()) break;
    L.P = level.prolongation;
    if (L.P.rows() != L.A.rows() || L.P.cols() != levels[l + 1].layout.num_free())
      throw std::invalid_argument("multigrid: a prolongation does not match its levels");
    galerkin(L.A, L.P, built[l + 1].A);
    // The smoother: each patch's box of interior functions, and the strip.
    std::vector<int> shared(level.layout.dof.size(), 0);
    for (const MultigridPatch& patch : level.patches)
      for (int f : patch.function) ++shared[f];
    const int n = level.layout.num_free();
    std::vector<char> in_box(n, 0), in_strip(n, 0);
    const Eigen::VectorXd diagonal = L.A.diagonal();
    L.boxes.resize(level.patches.size());
    L.blocks.assign(options.tilings, {});
    for (size_t k = 0; k < level.patches.size(); ++k) {
      PatchBox& box = L.boxes[k];
      if (!make_box(level, k, shared, layers, box, in_strip)) return nullptr;
      if (box.dof.empty()) continue;  // no interior function: the strip holds them all
      build_windows(box.u, block, options.tilings);
      build_windows(box.v, block, options.tilings);
      box.scale.resize(static_cast<long>(box.dof.size()));
      for (int b = 0; b < box.v.count; ++b)
        for (int a = 0; a < box.u.count; ++a) {
          const long i = a + static_cast<long>(box.u.count) * b;
          const int d = box.dof[i];
          in_box[d] = 1;
          const double s = box.u.stiffness_diagonal[a] * box.v.mass_diagonal[b] + box.u.mass_diagonal[a] * box.v.stiffness_diagonal[b];
          box.scale[i] = diagonal[d] > 0 && s > 0 ? std::sqrt(s / diagonal[d]) : 1.0;
        }
      // Blocks of one colour: windows an even number apart in each direction, in any patch.
      int offset_u = 0, offset_v = 0;
      for (int t = 0; t < options.tilings; ++t) {
        const int wu = static_cast<int>(box.u.tilings[t].size()), wv = static_cast<int>(box.v.tilings[t].size());
        for (int b = 0; b < wv; ++b)
          for (int a = 0; a < wu; ++a)
            L.blocks[t][(a & 1) + 2 * (b & 1)].push_back({static_cast<int>(k), offset_u + a, offset_v + b});
        offset_u += wu, offset_v += wv;
      }
    }
    for (int d = 0; d < n; ++d)
      if (!in_box[d] || in_strip[d]) L.strip.push_back(d);
    if (!L.strip.empty()) {
      std::vector<int> at(n, -1);
      for (size_t s = 0; s < L.strip.size(); ++s) at[L.strip[s]] = static_cast<int>(s);
      std::vector<Eigen::Triplet<double>> t;
      for (size_t s = 0; s < L.strip.size(); ++s)
        for (RowMatrix::InnerIterator e(L.A, L.strip[s]); e; ++e)
          if (at[e.col()] >= 0 && at[e.col()] <= static_cast<int>(s)) t.emplace_back(static_cast<int>(s), at[e.col()], e.value());
      Eigen::SparseMatrix<double> S(static_cast<long>(L.strip.size()), static_cast<long>(L.strip.size()));
      S.setFromTriplets(t.begin(), t.end());
      L.strip_factor = std::make_unique<Eigen::SimplicialLLT<Eigen::SparseMatrix<double>>>(S);
      if (L.strip_factor->info() != Eigen::Success)
        throw std::runtime_error("multigrid: the interface strip's block is not positive definite");
    }
    if (report) report->strip_dofs.push_back(static_cast<long>(L.strip.size()));
  }
  const Eigen::SparseMatrix<double> coarsest = built.back().A;
  built.back().A = RowMatrix();
  return std::make_unique<PatchwiseMultigrid>(std::move(built), coarsest);
}

}  // namespace knotwork
