#include "solver/tensor_rediscretize.hpp"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "solver/tensor_multigrid.hpp"

namespace knotwork {

namespace {

// Coefficients c_f (n_fu x n_fv, column-major) of a spline on the fine elements, moved to the
// coarse space: c_c = argmin |(T_v (x) T_u) c_c - c_f|, one direction at a time through the
// normal equations (T^T T is banded and well conditioned: B-spline bases are stable). False
// when c_c does not reproduce c_f to `tolerance` times its largest entry.
bool remove_knots(const Eigen::MatrixXd& fine, const Eigen::SparseMatrix<double>* Tu, const Eigen::SparseMatrix<double>* Tv,
                  Eigen::MatrixXd& coarse) {
  auto solve = [](const Eigen::SparseMatrix<double>& T, const Eigen::MatrixXd& c) -> Eigen::MatrixXd {
    const Eigen::SparseMatrix<double> normal = T.transpose() * T;
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(normal);
    if (ldlt.info() != Eigen::Success) return {};
    return ldlt.solve(Eigen::MatrixXd(T.transpose() * c));
  };
  Eigen::MatrixXd t = Tu ? solve(*Tu, fine) : fine;
  if (t.size() == 0) return false;
  if (Tv) {
    const Eigen::MatrixXd s = solve(*Tv, t.transpose());
    if (s.size() == 0) return false;
    coarse = s.transpose();
  } else {
    coarse = std::move(t);
  }
  Eigen::MatrixXd back = Tu ? Eigen::MatrixXd(*Tu * coarse) : coarse;
  if (Tv) back = Eigen::MatrixXd(back * Tv->transpose());
  // A decision, not an accuracy claim: where the geometry lives on the coarse elements the
  // residual is rounding (measured 1e-16..1e-15 of the net); where a removed breakpoint is a
  // kink of the geometry it is the kink's size. A coarse level on a slightly wrong geometry
  // would only weaken the preconditioner (CG applies the fine operator), never the solution.
  const double scale = std::max(1.0, fine.cwiseAbs().maxCoeff());
  return (back - fine).cwiseAbs().maxCoeff() <= 1e-9 * scale;
}

}  // namespace

std::unique_ptr<TensorPoissonOperator> rediscretized_operator(const TensorPoissonOperator& fine, bool halve_u,
                                                              bool halve_v) {
  BSplineBasis1D su = fine.space_u(), sv = fine.space_v(), gu = fine.geometry_u(), gv = fine.geometry_v();
  if (halve_u && !(halved_basis(fine.space_u(), su) && halved_basis(fine.geometry_u(), gu))) return nullptr;
  if (halve_v && !(halved_basis(fine.space_v(), sv) && halved_basis(fine.geometry_v(), gv))) return nullptr;
  // A map affine on the whole patch is the same on every mesh, and so are its factors.
  if (fine.uniform_factors())
    return TensorPoissonOperator::uniformly_affine(su, sv, fine.factors(), fine.stiffness(), fine.reaction(), fine.points_u(),
                                                   fine.points_v());
  std::optional<Eigen::SparseMatrix<double>> Tu, Tv;
  if (halve_u) Tu = refinement_matrix(gu, fine.geometry_u());
  if (halve_v) Tv = refinement_matrix(gv, fine.geometry_v());
  const Eigen::MatrixX3d& net = fine.net();
  const int fu = fine.geometry_u().num_functions(), fv = fine.geometry_v().num_functions();
  Eigen::MatrixX3d coarse_net(long(gu.num_functions()) * gv.num_functions(), 3);
  for (int k = 0; k < 3; ++k) {
    const Eigen::MatrixXd c = Eigen::Map<const Eigen::MatrixXd>(net.col(k).data(), fu, fv);
    Eigen::MatrixXd r;
    if (!remove_knots(c, Tu ? &*Tu : nullptr, Tv ? &*Tv : nullptr, r)) return nullptr;
    coarse_net.col(k) = Eigen::Map<const Eigen::VectorXd>(r.data(), r.size());
  }
  Eigen::VectorXd weights;
  if (fine.weights().size() > 0) {
    std::optional<Eigen::SparseMatrix<double>> Su, Sv;
    if (halve_u) Su = refinement_matrix(su, fine.space_u());
    if (halve_v) Sv = refinement_matrix(sv, fine.space_v());
    const Eigen::MatrixXd w =
        Eigen::Map<const Eigen::MatrixXd>(fine.weights().data(), fine.space_u().num_functions(), fine.space_v().num_functions());
    Eigen::MatrixXd r;
    if (!remove_knots(w, Su ? &*Su : nullptr, Sv ? &*Sv : nullptr, r) || !(r.minCoeff() > 0)) return nullptr;
    weights = Eigen::Map<const Eigen::VectorXd>(r.data(), r.size());
  }
  return std::make_unique<TensorPoissonOperator>(TensorPatch{&su, &sv, &weights, &gu, &gv, &coarse_net}, fine.stiffness(),
                                                 fine.reaction(), fine.points_u(), fine.points_v());
}

Eigen::SparseMatrix<double, Eigen::RowMajor> matrix_by_probing(const TensorPoissonOperator& op,
                                                               const TensorPoissonOperator::FunctionBox& free) {
  const int pu = op.space_u().degree(), pv = op.space_v().degree(), su = 2 * pu + 1, sv = 2 * pv + 1;
  const int nu = free.count_u, nv = free.count_v;
  const long n = long(nu) * nv;
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(size_t(n) * su * sv);
  Eigen::VectorXd x(n), y(n);
  // The column of colour c within a degree of index a: a - r or a - r + s, r = (a - c) mod s.
  auto partner = [](int a, int c, int s, int p) {
    const int r = ((a - c) % s + s) % s;
    return r <= p ? a - r : a - r + s;
  };
  for (int cv = 0; cv < sv; ++cv)
    for (int cu = 0; cu < su; ++cu) {
      for (int b = 0; b < nv; ++b)
        for (int a = 0; a < nu; ++a) x[a + long(nu) * b] = a % su == cu && b % sv == cv ? 1.0 : 0.0;
      op.apply_within(x.data(), free, y.data());
      for (int b = 0; b < nv; ++b)
        for (int a = 0; a < nu; ++a) {
          const int a2 = partner(a, cu, su, pu), b2 = partner(b, cv, sv, pv);
          if (a2 < 0 || a2 >= nu || b2 < 0 || b2 >= nv) continue;
          const long row = a + long(nu) * b;
          entries.emplace_back(int(row), int(a2 + long(nu) * b2), y[row]);
        }
    }
  Eigen::SparseMatrix<double, Eigen::RowMajor> A(n, n);
  A.setFromTriplets(entries.begin(), entries.end());
  // K_ij and K_ji come from the same integrals summed in other orders: symmetric to rounding,
  // and made exactly so for the Cholesky factor and the Galerkin products below it.
  Eigen::SparseMatrix<double, Eigen::RowMajor> At = A.transpose();
  A = 0.5 * (A + At);
  return A;
}

}  // namespace knotwork
