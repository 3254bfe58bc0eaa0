#include "solver/patchwise_multigrid.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

#include "basis/core/disjoint_sets.hpp"
#include "solver/linear_solver.hpp"
#include "solver/tensor_multigrid.hpp"
#include "solver/tensor_multigrid_levels.hpp"

namespace knotwork {

namespace {

using namespace multigrid_levels;

// Knot insertion computes its coefficients through Bezier extraction: a coefficient that is
// zero in exact arithmetic may come out as rounding (below 1e-15; the coefficients lie in
// [0, 1]). Below this it is zero: it must not make an interior function fixed or glued.
constexpr double kZeroCoefficient = 1e-12;

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

// Which patches hold each function of a level (a patch twice across a seam; several: the
// function is on an interface), in compressed rows, without an allocation per function: the
// holders of f are patch[start[f]] .. patch[start[f + 1] - 1], ascending.
struct Holders {
  std::vector<long> start;
  std::vector<int> patch;
  long count(int f) const { return start[f + 1] - start[f]; }
};

Holders holders_of(const PatchwiseLevel& level) {
  const int n = static_cast<int>(level.layout.dof.size());
  Holders h;
  h.start.assign(n + 1, 0);
  for (const MultigridPatch& p : level.patches)
    for (int f : p.function) ++h.start[f + 1];
  for (int f = 0; f < n; ++f) h.start[f + 1] += h.start[f];
  h.patch.resize(h.start.back());
  std::vector<long> next(h.start.begin(), h.start.end() - 1);
  for (size_t k = 0; k < level.patches.size(); ++k)
    for (int f : level.patches[k].function) h.patch[next[f]++] = static_cast<int>(k);
  return h;
}

// The number of functions of a patch per direction (1 in a missing third direction).
std::array<int, 3> counts_of(const MultigridPatch& p) {
  std::array<int, 3> n{1, 1, 1};
  for (size_t d = 0; d < p.bases.size(); ++d) n[d] = p.bases[d].num_functions();
  return n;
}

}  // namespace

MultigridPatch planar_multigrid_patch(const BSplineBasis1D& u, const BSplineBasis1D& v, const SeparableCoefficients& fit,
                                      const NitscheEnds& nitsche, std::vector<int> function) {
  MultigridPatch p;
  p.bases = {u, v};
  p.stiffness_weight = {fit.a1, fit.b2};
  p.mass_weight = {fit.a2, fit.b1};
  const auto& side = nitsche.sides;  // bottom, right, top, left
  p.nitsche = {{side[3], side[1]}, {side[0], side[2]}};
  p.nitsche_factor = nitsche.factor;
  p.function = std::move(function);
  return p;
}

MultigridPatch volume_multigrid_patch(const std::array<BSplineBasis1D, 3>& bases, const SeparableVolumeCoefficients& fit,
                                      std::vector<int> function, const std::array<bool, 6>& nitsche, double nitsche_factor) {
  MultigridPatch p;
  p.bases.assign(bases.begin(), bases.end());
  p.stiffness_weight.assign(fit.tau.begin(), fit.tau.end());
  p.mass_weight.assign(fit.mu.begin(), fit.mu.end());
  for (int d = 0; d < 3; ++d) p.nitsche.push_back({nitsche[2 * d], nitsche[2 * d + 1]});
  p.nitsche_factor = nitsche_factor;
  p.function = std::move(function);
  return p;
}

bool coarser_level(PatchwiseLevel& fine, PatchwiseLevel& coarse) {
  const size_t np = fine.patches.size();
  std::vector<MultigridPatch> patches(np);
  for (size_t k = 0; k < np; ++k) {
    const MultigridPatch& f = fine.patches[k];
    MultigridPatch& c = patches[k];
    c.bases.resize(f.bases.size());
    for (size_t d = 0; d < f.bases.size(); ++d)
      if (!halved_basis(f.bases[d], c.bases[d])) return false;
    for (size_t d = 0; d < f.bases.size(); ++d) {
      c.mass_weight.push_back(d < f.mass_weight.size() ? merged_weights(f.bases[d], c.bases[d], f.mass_weight[d])
                                                       : std::vector<double>{});
      c.stiffness_weight.push_back(d < f.stiffness_weight.size()
                                       ? merged_weights(f.bases[d], c.bases[d], f.stiffness_weight[d])
                                       : std::vector<double>{});
    }
    c.nitsche = f.nitsche;
    c.nitsche_factor = f.nitsche_factor;
  }
  const Holders holders = holders_of(fine);
  // Patch k's knot insertion per direction, transposed (row: a coarse function's fine ones).
  using RowMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor>;
  std::vector<std::array<RowMatrix, 3>> insertion(np);
  std::vector<std::array<int, 3>> nf(np), nc(np);
  std::vector<long> first_coarse{0};  // patch k's coarse functions: first_coarse[k] + local index
  for (size_t k = 0; k < np; ++k) {
    const MultigridPatch& F = fine.patches[k];
    nf[k] = counts_of(F), nc[k] = counts_of(patches[k]);
    if (F.function.size() != static_cast<size_t>(nf[k][0]) * nf[k][1] * nf[k][2])
      throw std::invalid_argument("multigrid: a patch's function numbering does not match its bases");
    for (size_t d = 0; d < 3; ++d) {
      if (d < F.bases.size()) {
        insertion[k][d] = RowMatrix(Eigen::SparseMatrix<double>(refinement_matrix(patches[k].bases[d], F.bases[d])).transpose());
      } else {
        insertion[k][d].resize(1, 1);
        insertion[k][d].insert(0, 0) = 1.0;
      }
    }
    first_coarse.push_back(first_coarse.back() + static_cast<long>(nc[k][0]) * nc[k][1] * nc[k][2]);
  }
  // Coarse function `local` of patch k: its fine functions and coefficients, by fine number.
  auto refined = [&](size_t k, long local, std::vector<std::pair<int, double>>& column) {
    column.clear();
    const long c0 = local % nc[k][0], c1 = (local / nc[k][0]) % nc[k][1], c2 = local / (long(nc[k][0]) * nc[k][1]);
    const std::vector<int>& fn = fine.patches[k].function;
    for (RowMatrix::InnerIterator z(insertion[k][2], c2); z; ++z)
      for (RowMatrix::InnerIterator y(insertion[k][1], c1); y; ++y)
        for (RowMatrix::InnerIterator x(insertion[k][0], c0); x; ++x) {
          const double value = x.value() * y.value() * z.value();
          if (std::abs(value) >= kZeroCoefficient)
            column.emplace_back(fn[x.col() + nf[k][0] * (y.col() + static_cast<long>(nf[k][1]) * z.col())], value);
        }
    std::sort(column.begin(), column.end());
  };
  // Coarse functions of patches a and b (a <= b; a = b across a seam) are one glued function
  // when their coefficients on the fine functions both patches hold are the same and not all
  // zero: the same trace on what the two patches share. (Comparing all shared fine functions
  // would part the copies of a vertex function in two patches that meet only at the vertex.)
  DisjointSets glued(static_cast<int>(first_coarse.back()));
  std::map<std::pair<std::pair<int, int>, std::vector<int>>, std::pair<int, std::vector<double>>> seen;
  std::vector<std::pair<int, double>> column;
  for (size_t k = 0; k < np; ++k)
    for (long local = 0; local < first_coarse[k + 1] - first_coarse[k]; ++local) {
      refined(k, local, column);
      std::map<int, std::pair<std::vector<int>, std::vector<double>>> with;  // partner patch -> its key
      for (const auto& [g, v] : column) {
        const int* h = holders.patch.data() + holders.start[g];
        const long count = holders.count(g);
        if (count < 2) continue;
        for (long i = 0; i < count; ++i) {
          // Held by this patch and h[i] (this patch itself only when it holds g twice).
          if (h[i] == static_cast<int>(k) && std::count(h, h + count, h[i]) < 2) continue;
          if (i > 0 && h[i] == h[i - 1]) continue;
          auto& [ids, values] = with[h[i]];
          ids.push_back(g), values.push_back(v);
        }
      }
      const int me = static_cast<int>(first_coarse[k] + local);
      for (auto& [partner, key] : with) {
        const std::pair<int, int> pair = std::minmax(static_cast<int>(k), partner);  // (copied: minmax returns references)
        auto [at, inserted] = seen.try_emplace({pair, key.first}, me, key.second);
        if (inserted) continue;
        for (size_t i = 0; i < key.second.size(); ++i)
          if (std::abs(key.second[i] - at->second.second[i]) > 1e-12)
            throw std::logic_error("multigrid: two patches refine a glued function differently (a non-conforming interface)");
        glued.unite(me, at->second.first);
      }
    }
  int coarse_functions = 0;
  const std::vector<int> number = glued.numbering(&coarse_functions);
  // Each patch gives the prolongation's entries of its fine functions; a fine function that
  // several patches (or one, twice) hold gets the same entries from each, kept once. Whether a
  // coarse function reaches a fixed function, from every patch.
  std::vector<char> fixed(coarse_functions, 0);
  struct Entry {
    int fine, coarse;
    double value;
  };
  std::vector<Entry> entries;
  for (size_t k = 0; k < np; ++k) {
    MultigridPatch& C = patches[k];
    C.function.resize(first_coarse[k + 1] - first_coarse[k]);
    for (long local = 0; local < first_coarse[k + 1] - first_coarse[k]; ++local) {
      const int c = number[first_coarse[k] + local];
      C.function[local] = c;
      refined(k, local, column);
      for (const auto& [g, v] : column) {
        if (fine.layout.dof[g] < 0)
          fixed[c] = 1;
        else
          entries.push_back({fine.layout.dof[g], c, v});
      }
    }
  }
  coarse.patches = std::move(patches);
  coarse.layout = make_dof_layout(coarse_functions, std::vector<bool>(fixed.begin(), fixed.end()));
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(entries.size());
  for (const Entry& e : entries)
    if (const int c = coarse.layout.dof[e.coarse]; c >= 0) triplets.emplace_back(e.fine, c, e.value);
  fine.prolongation.resize(fine.layout.num_free(), coarse.layout.num_free());
  fine.prolongation.setFromTriplets(triplets.begin(), triplets.end(), [](double first, double) { return first; });
  return true;
}

namespace {

// A patch's interior functions on one level: a box of its univariate indices (a volume's, or a
// planar patch's with a third direction of one function).
struct PatchBox {
  std::array<Direction, 3> d;
  std::vector<int> dof;   // a + n_u (b + n_v c) over the box -> the level's free dof
  Eigen::VectorXd scale;  // D^{-1/2}, D = diag(A) / diag(the separable operator)
  double shift = 0;       // the separable operator's reaction term: shift M_u (x) M_v (x) M_w
  std::array<int, 3> counts() const { return {d[0].count, d[1].count, d[2].count}; }
};

struct Block {
  int patch;
  std::array<int, 3> window;  // per direction, the window's index over all tilings in order
};

struct Level {
  RowMatrix A;  // the whole matrix over the level's free dofs
  std::vector<PatchBox> boxes;
  std::vector<std::vector<std::vector<Block>>> blocks;  // per tiling, per colour
  std::vector<int> strip;                                // the free dofs the band solves
  std::unique_ptr<SparseCholesky> strip_factor;
  RowMatrix P;  // from the next coarser level
};

// A direction of one function with the eigenpair (1, 0): a planar patch's third direction.
Direction trivial_direction(int tilings) {
  Direction d;
  d.first = 0, d.count = 1;
  d.mass_diagonal = Eigen::VectorXd::Ones(1);
  d.stiffness_diagonal = Eigen::VectorXd::Zero(1);
  d.mass_row_sum = Eigen::VectorXd::Ones(1);
  Window w;
  w.begin = 0, w.size = 1;
  w.U = Eigen::MatrixXd::Ones(1, 1);
  w.lambda = Eigen::VectorXd::Zero(1);
  d.tilings.assign(tilings, {w});
  return d;
}

// The box of patch `k`'s interior functions (box.dof empty when it has none), its band
// functions marked in `in_strip`; false when they are not a box.
bool make_box(const PatchwiseLevel& level, size_t k, const Holders& holders, int layers, int block, int tilings,
              PatchBox& box, std::vector<char>& in_strip) {
  const MultigridPatch& patch = level.patches[k];
  const int dim = static_cast<int>(patch.bases.size());
  const std::array<int, 3> n = counts_of(patch);
  auto function = [&](const std::array<int, 3>& i) { return patch.function[i[0] + n[0] * (i[1] + static_cast<long>(n[1]) * i[2])]; };
  auto own = [&](const std::array<int, 3>& i) {
    const int f = function(i);
    return level.layout.dof[f] >= 0 && holders.count(f) == 1;
  };
  // Per direction and end: whether the face's functions are out of the box (fixed or on an
  // interface), and whether it is an interface; judged on the face's functions off its edges,
  // which belong to the neighbouring faces too.
  std::array<std::array<bool, 2>, 3> out{}, interface{};
  for (int d = 0; d < dim; ++d)
    for (int end = 0; end < 2; ++end) {
      const int a = (d + 1) % 3, b = (d + 2) % 3;
      const int a0 = a < dim ? 1 : 0, a1 = a < dim ? n[a] - 1 : 1, b0 = b < dim ? 1 : 0, b1 = b < dim ? n[b] - 1 : 1;
      std::array<int, 3> i{};
      i[d] = end == 0 ? 0 : n[d] - 1;
      for (i[a] = a0; i[a] < a1; ++i[a])
        for (i[b] = b0; i[b] < b1; ++i[b]) {
          if (!own(i)) out[d][end] = true;
          if (holders.count(function(i)) > 1) interface[d][end] = true;
        }
    }
  std::array<int, 3> first{}, last{};
  for (int d = 0; d < 3; ++d) {
    first[d] = d < dim ? out[d][0] : 0;
    last[d] = d < dim ? n[d] - 1 - out[d][1] : 0;
    if (last[d] < first[d]) return true;  // none (a patch one function wide between interfaces)
  }
  std::array<int, 3> i;
  for (i[2] = first[2]; i[2] <= last[2]; ++i[2])
    for (i[1] = first[1]; i[1] <= last[1]; ++i[1])
      for (i[0] = first[0]; i[0] <= last[0]; ++i[0])
        if (!own(i)) return false;
  for (int d = 0; d < 3; ++d) {
    if (d >= dim) {
      box.d[d] = trivial_direction(tilings);
      continue;
    }
    Direction& D = box.d[d];
    D.basis = patch.bases[d];
    D.first = first[d];
    D.count = last[d] - first[d] + 1;
    D.fixed_at_end = n[d] - 1 - last[d];
    if (d < static_cast<int>(patch.mass_weight.size())) D.mass_weight = patch.mass_weight[d];
    if (d < static_cast<int>(patch.stiffness_weight.size())) D.stiffness_weight = patch.stiffness_weight[d];
    if (d < static_cast<int>(patch.nitsche.size())) D.nitsche_start = patch.nitsche[d][0], D.nitsche_end = patch.nitsche[d][1];
    D.nitsche_factor = patch.nitsche_factor;
    build_windows(D, block, tilings);
  }
  const std::array<int, 3> c = box.counts();
  box.dof.resize(static_cast<size_t>(c[0]) * c[1] * c[2]);
  std::array<int, 3> a;
  long at = 0;
  for (a[2] = 0; a[2] < c[2]; ++a[2])
    for (a[1] = 0; a[1] < c[1]; ++a[1])
      for (a[0] = 0; a[0] < c[0]; ++a[0], ++at) {
        std::array<int, 3> fi;
        bool near = false;
        for (int d = 0; d < 3; ++d) {
          fi[d] = first[d] + a[d];
          near = near || (d < dim && ((interface[d][0] && a[d] < layers) || (interface[d][1] && a[d] >= c[d] - layers)));
        }
        const int dof = level.layout.dof[function(fi)];
        box.dof[at] = dof;
        if (near) in_strip[dof] = 1;
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

// The lower triangle of A's principal block over `rows` (ascending), column-major.
Eigen::SparseMatrix<double> principal_lower(const RowMatrix& A, const std::vector<int>& rows) {
  std::vector<int> at(A.rows(), -1);
  for (size_t s = 0; s < rows.size(); ++s) at[rows[s]] = static_cast<int>(s);
  std::vector<Eigen::Triplet<double>> t;
  for (size_t s = 0; s < rows.size(); ++s)
    for (RowMatrix::InnerIterator e(A, rows[s]); e; ++e)
      if (at[e.col()] >= 0 && at[e.col()] <= static_cast<int>(s)) t.emplace_back(static_cast<int>(s), at[e.col()], e.value());
  Eigen::SparseMatrix<double> S(static_cast<long>(rows.size()), static_cast<long>(rows.size()));
  S.setFromTriplets(t.begin(), t.end());
  return S;
}

const Window& nth_window(const Direction& d, int n) {
  for (const std::vector<Window>& t : d.tilings) {
    if (n < static_cast<int>(t.size())) return t[n];
    n -= static_cast<int>(t.size());
  }
  throw std::logic_error("multigrid: a block's window is out of range");
}

class PatchwiseMultigrid final : public Preconditioner {
 public:
  PatchwiseMultigrid(std::vector<Level> levels, const Eigen::SparseMatrix<double>& coarsest_lower, bool volume)
      : levels_(std::move(levels)), work_(levels_.size()), coarse_(resolve_ordering(Ordering::kAuto, volume)) {
    coarse_.factorize(coarsest_lower);
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
      for (size_t c = 0; c < L.blocks[t].size(); ++c) sweep(L, L.blocks[t][c], b, x, /*x_is_zero=*/t == 0 && c == 0);
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
      for (int c = static_cast<int>(L.blocks[t].size()) - 1; c >= 0; --c) sweep(L, L.blocks[t][c], b, x);
  }

  // x_S += A_SS^{-1} (b - A x)_S on the band S.
  static void solve_strip(const Level& L, const Eigen::VectorXd& b, Eigen::VectorXd& x, Work& w) {
    if (L.strip.empty()) return;
    const int n = static_cast<int>(L.strip.size());
    w.strip_residual.resize(n);
#pragma omp parallel for schedule(static)
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
      const Window& U = nth_window(box.d[0], blocks[k].window[0]);
      const Window& V = nth_window(box.d[1], blocks[k].window[1]);
      const Window& W = nth_window(box.d[2], blocks[k].window[2]);
      const long nu = box.d[0].count, nv = box.d[1].count;
      thread_local Eigen::VectorXd R, T;
      R.resize(long(U.size) * V.size * W.size);
      T.resize(R.size());
      long at = 0;
      for (int l = 0; l < W.size; ++l)
        for (int j = 0; j < V.size; ++j)
          for (int i = 0; i < U.size; ++i, ++at) {
            const long a = U.begin + i + nu * (V.begin + j + nv * (W.begin + l));
            const int d = box.dof[a];
            R[at] = (x_is_zero ? b[d] : b[d] - row_dot(L.A, d, x.data())) * box.scale[a];
          }
      solve_in_eigenbases(U, V, W, R, T, box.shift);
      at = 0;
      for (int l = 0; l < W.size; ++l)
        for (int j = 0; j < V.size; ++j)
          for (int i = 0; i < U.size; ++i, ++at) {
            const long a = U.begin + i + nu * (V.begin + j + nv * (W.begin + l));
            x[box.dof[a]] += box.scale[a] * R[at];
          }
    }
  }

  std::vector<Level> levels_;
  mutable std::vector<Work> work_;
  mutable SparseCholesky coarse_;
};

}  // namespace

std::unique_ptr<Preconditioner> patchwise_multigrid(PatchwiseLevel finest, const Eigen::SparseMatrix<double>& lower,
                                                    const PatchwiseMultigridOptions& options,
                                                    PatchwiseMultigridReport* report) {
  if (finest.patches.empty()) throw std::invalid_argument("multigrid: no patch");
  const bool volume = finest.patches.front().bases.size() == 3;
  int p = 1;
  for (const MultigridPatch& patch : finest.patches)
    for (const BSplineBasis1D& b : patch.bases) p = std::max(p, b.degree());
  const int block = block_side(options.block, p);
  const int layers = options.strip_layers >= 0 ? options.strip_layers : p;
  std::vector<PatchwiseLevel> levels;
  levels.push_back(std::move(finest));
  while (levels.back().layout.num_free() > options.coarsest_functions) {
    PatchwiseLevel next;
    if (!coarser_level(levels.back(), next)) break;
    levels.push_back(std::move(next));
  }
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
    galerkin(L.A, L.P, built[l + 1].A);
    // The smoother: each patch's box of interior functions, and the band.
    const Holders holders = holders_of(level);
    const int n = level.layout.num_free();
    std::vector<char> in_box(n, 0), in_strip(n, 0);
    const Eigen::VectorXd diagonal = L.A.diagonal();
    L.boxes.resize(level.patches.size());
    const int colours = volume ? 8 : 4;
    L.blocks.assign(options.tilings, std::vector<std::vector<Block>>(colours));
    for (size_t k = 0; k < level.patches.size(); ++k) {
      PatchBox& box = L.boxes[k];
      if (!make_box(level, k, holders, layers, block, options.tilings, box, in_strip)) return nullptr;
      if (box.dof.empty()) continue;  // no interior function: the band holds them all
      const std::array<int, 3> c = box.counts();
      // The separable operator's diagonal is stiffness[i] + shift mass[i]: stiffness the sum
      // over directions of K_d (x) M_others, mass the product of the M_d. The shift stands for
      // a reaction term c u, which the stiffness's fit leaves out (with c = 1000 on 12 curved
      // patches CG did not converge without it). Stiffness matrices annihilate constants, so on rows whose
      // couplings all lie in the box, A 1 is the reaction's part alone, whatever the diffusion;
      // the shift makes the separable operator's (M_u 1) (x) (M_v 1) (x) (M_w 1) match it there.
      const long nb = static_cast<long>(box.dof.size());
      Eigen::VectorXd stiffness(nb), mass(nb);
      std::array<int, 3> reach{};  // the degree (how far a row couples), per direction
      for (int e = 0; e < (volume ? 3 : 2); ++e) reach[e] = box.d[e].basis.degree();
      double reaction = 0, model = 0;
      long at = 0;
      for (int k2 = 0; k2 < c[2]; ++k2)
        for (int k1 = 0; k1 < c[1]; ++k1)
          for (int k0 = 0; k0 < c[0]; ++k0, ++at) {
            const std::array<int, 3> i{k0, k1, k2};
            stiffness[at] = 0;
            mass[at] = 1;
            bool inside = true;
            double sums = 1;
            for (int e = 0; e < 3; ++e) {
              double term = box.d[e].stiffness_diagonal[i[e]];
              for (int o = 0; o < 3; ++o)
                if (o != e) term *= box.d[o].mass_diagonal[i[o]];
              stiffness[at] += term;
              mass[at] *= box.d[e].mass_diagonal[i[e]];
              sums *= box.d[e].mass_row_sum[i[e]];
              inside = inside && i[e] >= reach[e] && i[e] < c[e] - reach[e];
            }
            if (!inside) continue;
            for (RowMatrix::InnerIterator a(L.A, box.dof[at]); a; ++a) reaction += a.value();
            model += sums;
          }
      box.shift = model > 0 && reaction > 0 ? reaction / model : 0.0;
      box.scale.resize(nb);
      for (long j = 0; j < nb; ++j) {
        const int d = box.dof[j];
        in_box[d] = 1;
        const double s = stiffness[j] + box.shift * mass[j];
        box.scale[j] = diagonal[d] > 0 && s > 0 ? std::sqrt(s / diagonal[d]) : 1.0;
      }
      // Blocks of one colour: windows an even number apart in each direction, in any patch.
      std::array<int, 3> offset{};
      for (int t = 0; t < options.tilings; ++t) {
        std::array<int, 3> w;
        for (int e = 0; e < 3; ++e) w[e] = static_cast<int>(box.d[e].tilings[t].size());
        for (int z = 0; z < w[2]; ++z)
          for (int y = 0; y < w[1]; ++y)
            for (int x = 0; x < w[0]; ++x)
              L.blocks[t][(x & 1) + 2 * (y & 1) + 4 * (z & 1)].push_back(
                  {static_cast<int>(k), {offset[0] + x, offset[1] + y, offset[2] + z}});
        for (int e = 0; e < 3; ++e) offset[e] += w[e];
      }
    }
    for (int d = 0; d < n; ++d)
      if (!in_box[d] || in_strip[d]) L.strip.push_back(d);
    if (!L.strip.empty()) {
      L.strip_factor = std::make_unique<SparseCholesky>(resolve_ordering(Ordering::kAuto, volume));
      L.strip_factor->factorize(principal_lower(L.A, L.strip));
    }
    if (report) report->strip_dofs.push_back(static_cast<long>(L.strip.size()));
  }
  const Eigen::SparseMatrix<double> coarsest = built.back().A.triangularView<Eigen::Lower>();
  built.back().A = RowMatrix();
  return std::make_unique<PatchwiseMultigrid>(std::move(built), coarsest, volume);
}

}  // namespace knotwork
