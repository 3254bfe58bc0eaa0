// Written here: no library computes THB prolongations. One representative leaf per fine
// function (a leaf of the function's own level, thb_prolongation.hpp says why it suffices); on
// it the coarse functions' Bézier coefficients, restricted from their coarse leaf, are turned
// into the level's B-spline coefficients by the inverse of the level's local extraction.
#include "basis/thb/thb_prolongation.hpp"

#include <omp.h>

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <array>
#include <map>
#include <unordered_map>

#include "basis/core/bezier_ops.hpp"

namespace knotwork {

namespace {

// The coefficients are in [0, 1] (THB-splines are a nonnegative partition of unity, and so are
// their refinement coefficients): smaller ones are rounding of exact zeros.
constexpr double kDropped = 1e-13;

// B (p+1) x nb (columns b + (q+1) c) -> Su B (Sw (x) Sv)^T: a tensor coefficient block mapped
// along u by Su and along (v, w) by the Kronecker product (w outer, as the extraction's layout).
Eigen::MatrixXd across_directions(const Eigen::MatrixXd& Su, const Eigen::MatrixXd& Sv, const Eigen::MatrixXd* Sw,
                                  const Eigen::MatrixXd& block) {
  if (!Sw) return Su * block * Sv.transpose();
  Eigen::MatrixXd Svw(Sw->rows() * Sv.rows(), Sw->cols() * Sv.cols());
  for (Eigen::Index c = 0; c < Sw->rows(); ++c)
    for (Eigen::Index c2 = 0; c2 < Sw->cols(); ++c2)
      Svw.block(c * Sv.rows(), c2 * Sv.cols(), Sv.rows(), Sv.cols()) = (*Sw)(c, c2) * Sv;
  return Su * block * Svw.transpose();
}

}  // namespace

Eigen::SparseMatrix<double> thb_prolongation(const ThbHierarchy& hierarchy, const BezierMesh& coarse_mesh,
                                             const std::vector<ThbCell>& coarse_leaves, const BezierMesh& fine_mesh,
                                             const std::vector<ThbCell>& fine_leaves,
                                             const std::vector<int>& fine_functions_per_level) {
  const int d = hierarchy.dimension();
  const int p = hierarchy.knots(0).degree(), q = hierarchy.knots(1).degree(), r = d == 3 ? hierarchy.knots(2).degree() : 0;
  const int nb = (q + 1) * (r + 1);
  // The level of each fine function: THB numbers them level by level.
  std::vector<int> level_of(fine_mesh.num_functions());
  for (int l = 0, first = 0; l < static_cast<int>(fine_functions_per_level.size()); ++l) {
    std::fill(level_of.begin() + first, level_of.begin() + first + fine_functions_per_level[l], l);
    first += fine_functions_per_level[l];
  }
  // Each fine function's representative: the first leaf of its own level it lives on.
  std::vector<int> representative(fine_mesh.num_functions(), -1);
  std::vector<int> leaves_used;
  for (int c = 0; c < fine_mesh.num_cells(); ++c) {
    bool used = false;
    for (int f : fine_mesh.functions(c))
      if (representative[f] < 0 && level_of[f] == fine_leaves[c].level) representative[f] = c, used = true;
    if (used) leaves_used.push_back(c);
  }
  for (int f = 0; f < fine_mesh.num_functions(); ++f)
    if (representative[f] < 0) throw std::logic_error("THB prolongation: a function lives on no leaf of its level");
  // The coarse leaves by level and element indices.
  std::vector<std::unordered_map<ThbHierarchy::Key, int, ThbHierarchy::KeyHash>> coarse_at;
  for (int c = 0; c < static_cast<int>(coarse_leaves.size()); ++c) {
    const ThbCell& t = coarse_leaves[c];
    if (static_cast<int>(coarse_at.size()) <= t.level) coarse_at.resize(t.level + 1);
    coarse_at[t.level].emplace(ThbHierarchy::Key{t.i, t.j, t.k}, c);
  }
  using Triplets = std::vector<Eigen::Triplet<double>>;
  std::vector<Triplets> per_thread(omp_get_max_threads());
  // Per thread and direction, the tables leaves share: E^-T by (level, element), restrictions
  // by their sub-interval.
  struct Tables {
    std::map<std::pair<int, int64_t>, Eigen::MatrixXd> inverse;
    std::map<std::pair<double, double>, Eigen::MatrixXd> restriction;
  };
  std::vector<std::array<Tables, 3>> tables(omp_get_max_threads());
  std::vector<std::string> failure(omp_get_max_threads());
#pragma omp parallel for schedule(dynamic, 16)
  for (size_t n = 0; n < leaves_used.size(); ++n) {
    try {
      const int c = leaves_used[n];
      const ThbCell& t = fine_leaves[c];
      // The coarse leaf that holds this one: the same cell or an ancestor.
      int coarse = -1;
      for (int depth = 0; depth <= t.level && coarse < 0; ++depth) {
        const int l = t.level - depth;
        if (l >= static_cast<int>(coarse_at.size())) continue;
        const auto it = coarse_at[l].find({t.i >> depth, t.j >> depth, d == 3 ? t.k >> depth : 0});
        if (it != coarse_at[l].end()) coarse = it->second;
      }
      if (coarse < 0) throw std::logic_error("THB prolongation: a refined leaf lies in no leaf of the coarser space");
      const ThbCell& ct = coarse_leaves[coarse];
      // Restriction of Bernstein coefficients from the coarse leaf to this one, per direction.
      const int64_t index[3] = {t.i, t.j, t.k}, coarse_index[3] = {ct.i, ct.j, ct.k};
      std::array<Tables, 3>& mine = tables[omp_get_thread_num()];
      const Eigen::MatrixXd* S[3];
      for (int x = 0; x < d; ++x) {
        const DyadicKnots& K = hierarchy.knots(x);
        const double a = K.breakpoint(ct.level, coarse_index[x]), b = K.breakpoint(ct.level, coarse_index[x] + 1);
        const double s = (K.breakpoint(t.level, index[x]) - a) / (b - a), e = (K.breakpoint(t.level, index[x] + 1) - a) / (b - a);
        auto [it, fresh] = mine[x].restriction.try_emplace({s, e});
        if (fresh) it->second = subdivision_matrix(K.degree(), s, e);
        S[x] = &it->second;
      }
      // The inverse of the level's local extraction along each direction, transposed.
      const Eigen::MatrixXd* Einv_of[3];
      for (int x = 0; x < d; ++x) {
        auto [it, fresh] = mine[x].inverse.try_emplace({t.level, index[x]});
        if (fresh) it->second = hierarchy.knots(x).extraction(t.level, index[x]).inverse().transpose();
        Einv_of[x] = &it->second;
      }
      const Eigen::MatrixXd& E0 = *Einv_of[0];
      const Eigen::MatrixXd& E1 = *Einv_of[1];
      // X = Eu^-T beta (Ew (x) Ev)^-1 = Eu^-T beta (Ew^-T (x) Ev^-T)^T: the level's B-spline
      // coefficients of a Bernstein block.
      const auto bspline_coefficients = [&](const Eigen::MatrixXd& beta) {
        return across_directions(E0, E1, d == 3 ? Einv_of[2] : nullptr, beta);
      };
      const auto block = [&](const Eigen::MatrixXd& extraction, int row) {
        return Eigen::Map<const Eigen::MatrixXd>(extraction.row(row).eval().data(), p + 1, nb).eval();
      };
      // Which B-spline of the level each represented fine function is: its coefficients are a unit block.
      std::vector<std::pair<int, Eigen::Index>> represented;  // (fine function, entry of the block)
      const Eigen::MatrixXd& fine_extraction = fine_mesh.extraction(c);
      const auto fine_functions = fine_mesh.functions(c);
      for (size_t a = 0; a < fine_functions.size(); ++a) {
        const int f = fine_functions[a];
        if (representative[f] != c) continue;
        const Eigen::MatrixXd X = bspline_coefficients(block(fine_extraction, static_cast<int>(a)));
        Eigen::Index at;
        X.cwiseAbs().reshaped().maxCoeff(&at);
        if (std::abs(X.reshaped()(at) - 1) > 1e-8 || X.cwiseAbs().sum() - std::abs(X.reshaped()(at)) > 1e-8)
          throw std::logic_error("THB prolongation: a function of a leaf's own level is not one of the level's B-splines there");
        represented.emplace_back(f, at);
      }
      // A represented function, B-spline (a, col) of the level (at = a + (p+1) col, col = b + (q+1) c),
      // reads of a coarse function with Bernstein block beta the entry (a, col) of
      // Mu beta Mvw^T, M = E^-T S per direction (Mvw = Mw (x) Mv): one weight per Bernstein
      // entry, so that one product gives every coarse function's coefficients at once.
      Eigen::MatrixXd M[3];
      for (int x = 0; x < d; ++x) M[x] = *Einv_of[x] * *S[x];
      Eigen::MatrixXd weights((p + 1) * nb, static_cast<Eigen::Index>(represented.size()));
      for (size_t k = 0; k < represented.size(); ++k) {
        const Eigen::Index at = represented[k].second, a = at % (p + 1), col = at / (p + 1);
        const Eigen::Index b = col % (q + 1), c3 = col / (q + 1);
        for (int m3 = 0; m3 <= r; ++m3)
          for (int m2 = 0; m2 <= q; ++m2) {
            const double along_vw = M[1](b, m2) * (d == 3 ? M[2](c3, m3) : 1.0);
            for (int m1 = 0; m1 <= p; ++m1) weights(m1 + (p + 1) * (m2 + (q + 1) * m3), k) = M[0](a, m1) * along_vw;
          }
      }
      const Eigen::MatrixXd values = coarse_mesh.extraction(coarse) * weights;
      const auto coarse_functions = coarse_mesh.functions(coarse);
      for (size_t j = 0; j < coarse_functions.size(); ++j)
        for (size_t k = 0; k < represented.size(); ++k)
          if (std::abs(values(j, k)) > kDropped)
            per_thread[omp_get_thread_num()].emplace_back(represented[k].first, coarse_functions[j], values(j, k));
    } catch (const std::exception& e) {
      failure[omp_get_thread_num()] = e.what();
    }
  }
  for (const std::string& f : failure)
    if (!f.empty()) throw std::logic_error(f);
  Triplets all;
  for (Triplets& t : per_thread) all.insert(all.end(), t.begin(), t.end());
  Eigen::SparseMatrix<double> P(fine_mesh.num_functions(), coarse_mesh.num_functions());
  P.setFromTriplets(all.begin(), all.end());
  return P;
}

}  // namespace knotwork
