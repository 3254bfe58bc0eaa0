#include "solver/fast_diagonalization.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "quadrature/gauss_legendre.hpp"

namespace knotwork {

UnivariatePair univariate_pair(const BSplineBasis1D& b, const std::vector<double>& mass_weight,
                               const std::vector<double>& stiffness_weight, bool nitsche_start, bool nitsche_end,
                               double nitsche_factor) {
  const int p = b.degree(), n = b.num_functions();
  const QuadratureRule1D rule = gauss_legendre(p + 1);
  const auto& t = b.knots();
  std::vector<double> d(2 * (p + 1));
  const std::vector<int> spans = b.element_spans();
  std::vector<Eigen::Triplet<double>> mass, stiffness;
  mass.reserve(spans.size() * (p + 1) * (p + 1) * rule.size());
  stiffness.reserve(mass.capacity() + 2 * (p + 1) * (p + 1));
  for (size_t e = 0; e < spans.size(); ++e) {
    const int s = spans[e];
    const double a = t[s], h = t[s + 1] - t[s];
    const double wm = mass_weight.empty() ? 1.0 : mass_weight[e], ws = stiffness_weight.empty() ? 1.0 : stiffness_weight[e];
    for (int k = 0; k < rule.size(); ++k) {
      b.evaluate_derivatives(s, a + h * rule.nodes[k], 1, d.data());
      const double w = rule.weights[k] * h;
      for (int i = 0; i <= p; ++i)
        for (int j = 0; j <= p; ++j) {
          mass.emplace_back(s - p + i, s - p + j, wm * w * d[i] * d[j]);
          stiffness.emplace_back(s - p + i, s - p + j, ws * w * d[p + 1 + i] * d[p + 1 + j]);
        }
    }
  }
  // The 1D Nitsche terms (NitscheEnds) at the ends asked for, weighted like the stiffness on
  // the end element.
  for (int which = 0; which < 2; ++which) {
    if (!(which == 0 ? nitsche_start : nitsche_end)) continue;
    const size_t e = which == 0 ? 0 : spans.size() - 1;
    const int s = spans[e];
    const double h = t[s + 1] - t[s], w = stiffness_weight.empty() ? 1.0 : stiffness_weight[e];
    b.evaluate_derivatives(s, which == 0 ? t[s] : t[s + 1], 1, d.data());
    // Outward derivative: -d/du at the start, +d/du at the end.
    const double out = which == 0 ? -1.0 : 1.0, gamma = nitsche_factor * 2 * w * p * p / h;
    for (int i = 0; i <= p; ++i)
      for (int k = 0; k <= p; ++k)
        stiffness.emplace_back(s - p + i, s - p + k,
                               -w * out * (d[p + 1 + i] * d[k] + d[i] * d[p + 1 + k]) + gamma * d[i] * d[k]);
  }
  UnivariatePair r;
  r.mass.resize(n, n);
  r.stiffness.resize(n, n);
  r.mass.setFromTriplets(mass.begin(), mass.end());
  r.stiffness.setFromTriplets(stiffness.begin(), stiffness.end());
  return r;
}

SeparableCoefficients SeparableCoefficients::fit(int n_u, int n_v, const std::vector<double>& c11,
                                                 const std::vector<double>& c22, std::vector<int> rows,
                                                 std::vector<int> columns) {
  auto all = [](int n) {
    std::vector<int> v(n);
    for (int i = 0; i < n; ++i) v[i] = i;
    return v;
  };
  if (rows.empty()) rows = all(n_u);
  if (columns.empty()) columns = all(n_v);
  // log c(i, j) ~ alpha_i + beta_j in least squares: alpha_i the mean of row i over J, beta_j
  // the mean of column j over I minus the mean over I x J (on a full grid, the normal
  // equations' solution; for separable c, exact whatever I and J).
  auto fit_one = [&](const std::vector<double>& c, std::vector<double>& a, std::vector<double>& b) {
    auto log_c = [&](int i, int j) { return std::log(std::max(c[i + static_cast<size_t>(n_u) * j], 1e-300)); };
    a.assign(n_u, 0.0);
    b.assign(n_v, 0.0);
    double both = 0;
    for (int i = 0; i < n_u; ++i) {
      for (int j : columns) a[i] += log_c(i, j);
      a[i] /= static_cast<double>(columns.size());
    }
    for (int j = 0; j < n_v; ++j) {
      for (int i : rows) b[j] += log_c(i, j);
      b[j] /= static_cast<double>(rows.size());
    }
    for (int i : rows)
      for (int j : columns) both += log_c(i, j);
    both /= static_cast<double>(rows.size() * columns.size());
    for (double& x : a) x = std::exp(x);
    for (double& x : b) x = std::exp(x - both);
  };
  SeparableCoefficients s;
  fit_one(c11, s.a1, s.b1);
  fit_one(c22, s.a2, s.b2);
  return s;
}

bool tensor_free_indices(int nu, int nv, const DofLayout& layout, std::vector<int>& iu, std::vector<int>& iv) {
  iu.clear();
  iv.clear();
  if (static_cast<long>(layout.dof.size()) != static_cast<long>(nu) * nv) return false;
  // Free lines: i is free when function (i, j) is free for some j; the product test follows.
  std::vector<bool> free_u(nu, false), free_v(nv, false);
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i)
      if (layout.dof[i + nu * j] >= 0) free_u[i] = free_v[j] = true;
  for (int i = 0; i < nu; ++i)
    if (free_u[i]) iu.push_back(i);
  for (int j = 0; j < nv; ++j)
    if (free_v[j]) iv.push_back(j);
  if (static_cast<long>(iu.size()) * static_cast<long>(iv.size()) != layout.num_free()) return false;
  for (size_t b = 0; b < iv.size(); ++b)
    for (size_t a = 0; a < iu.size(); ++a)
      if (layout.dof[iu[a] + nu * iv[b]] != static_cast<int>(a + iu.size() * b)) return false;
  return true;
}

// C = op(A) op(B) through the BLAS (OpenBLAS here: threaded, and about 3x Eigen's own kernel
// on these sizes). The products are the whole cost of the preconditioner's application, so
// they go to the library that does them best.
extern "C" void dgemm_(const char* transa, const char* transb, const int* m, const int* n, const int* k,
                       const double* alpha, const double* a, const int* lda, const double* b, const int* ldb,
                       const double* beta, double* c, const int* ldc);

void blas_gemm(bool ta, bool tb, int m, int n, int k, const double* A, int lda, const double* B, int ldb, double* C,
               int ldc) {
  const double one = 1, zero = 0;
  dgemm_(ta ? "T" : "N", tb ? "T" : "N", &m, &n, &k, &one, A, &lda, B, &ldb, &zero, C, &ldc);
}

namespace {

void gemm(bool ta, bool tb, const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, Eigen::MatrixXd& C) {
  const int m = static_cast<int>(ta ? A.cols() : A.rows()), k = static_cast<int>(ta ? A.rows() : A.cols());
  const int n = static_cast<int>(tb ? B.rows() : B.cols());
  C.resize(m, n);
  blas_gemm(ta, tb, m, n, k, A.data(), static_cast<int>(A.rows()), B.data(), static_cast<int>(B.rows()), C.data(), m);
}

class FastDiagonalization final : public Preconditioner {
 public:
  FastDiagonalization(Eigen::MatrixXd Uu, Eigen::VectorXd lu, Eigen::MatrixXd Uv, Eigen::VectorXd lv,
                      Eigen::VectorXd scale, double shift)
      : Uu_(std::move(Uu)), Uv_(std::move(Uv)), scale_(std::move(scale)) {
    inverse_.resize(lu.size(), lv.size());
    for (Eigen::Index j = 0; j < lv.size(); ++j)
      for (Eigen::Index i = 0; i < lu.size(); ++i) inverse_(i, j) = 1.0 / (lu[i] + lv[j] + shift);
  }
  // z = D^{-1/2} (U_v (x) U_u) (Lambda_u (+) Lambda_v + shift)^{-1} (U_v (x) U_u)^T D^{-1/2} r, with
  // vectors as n_u x n_v matrices (i fastest): (A (x) B) vec(X) = vec(B X A^T).
  void apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const override {
    const Eigen::Index nu = Uu_.rows(), nv = Uv_.rows();
    thread_local Eigen::MatrixXd R, T, Y;
    R = Eigen::Map<const Eigen::MatrixXd>(r.data(), nu, nv);
    R.array() *= Eigen::Map<const Eigen::MatrixXd>(scale_.data(), nu, nv).array();
    gemm(true, false, Uu_, R, T);   // T = U_u^T R
    gemm(false, false, T, Uv_, Y);  // Y = T U_v
    Y.array() *= inverse_.array();
    gemm(false, false, Uu_, Y, T);  // T = U_u Y
    gemm(false, true, T, Uv_, R);   // R = T U_v^T
    R.array() *= Eigen::Map<const Eigen::MatrixXd>(scale_.data(), nu, nv).array();
    z = Eigen::Map<const Eigen::VectorXd>(R.data(), nu * nv);
  }

 private:
  Eigen::MatrixXd Uu_, Uv_, inverse_;
  Eigen::VectorXd scale_;  // D^{-1/2}, in dof order
};

// LAPACK's divide-and-conquer generalized symmetric eigensolver: measured 21.5 s for the two
// 2050 x 2050 problems of a 2048^2 mesh with Eigen's GeneralizedSelfAdjointEigenSolver.
extern "C" void dsygvd_(const int* itype, const char* jobz, const char* uplo, const int* n, double* a, const int* lda,
                        double* b, const int* ldb, double* w, double* work, const int* lwork, int* iwork,
                        const int* liwork, int* info);

}  // namespace

// K restricted to the free indices, and its generalized eigenvectors (U^T M U = I).
void diagonalize(const UnivariatePair& pair, const std::vector<int>& keep, Eigen::MatrixXd& U, Eigen::VectorXd& lambda) {
  const int n = static_cast<int>(keep.size());
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(n, n);
  U = Eigen::MatrixXd::Zero(n, n);
  std::vector<int> position(pair.mass.rows(), -1);
  for (int a = 0; a < n; ++a) position[keep[a]] = a;
  for (const auto* source : {&pair.mass, &pair.stiffness}) {
    Eigen::MatrixXd& into = source == &pair.mass ? m : U;
    for (int c = 0; c < source->outerSize(); ++c)
      for (Eigen::SparseMatrix<double>::InnerIterator it(*source, c); it; ++it)
        if (position[it.row()] >= 0 && position[c] >= 0) into(position[it.row()], position[c]) = it.value();
  }
  lambda.resize(n);
  const int itype = 1;
  int info = 0, lwork = -1, liwork = -1, iwork_size = 0;
  double work_size = 0;
  dsygvd_(&itype, "V", "L", &n, U.data(), &n, m.data(), &n, lambda.data(), &work_size, &lwork, &iwork_size, &liwork, &info);
  lwork = static_cast<int>(work_size);
  liwork = iwork_size;
  std::vector<double> work(static_cast<size_t>(std::max(lwork, 1)));
  std::vector<int> iwork(static_cast<size_t>(std::max(liwork, 1)));
  dsygvd_(&itype, "V", "L", &n, U.data(), &n, m.data(), &n, lambda.data(), work.data(), &lwork, iwork.data(), &liwork,
          &info);
  if (info != 0)
    throw std::runtime_error("fast diagonalization: LAPACK dsygvd failed (info " + std::to_string(info) +
                             "): the univariate mass matrix is not positive definite");
}

std::unique_ptr<Preconditioner> fast_diagonalization(const BSplineBasis1D& space_u, const BSplineBasis1D& space_v,
                                                     const DofLayout& layout, const Eigen::VectorXd& diag,
                                                     const SeparableCoefficients& geometry, const NitscheEnds& nitsche) {
  std::vector<int> iu, iv;
  if (!tensor_free_indices(space_u.num_functions(), space_v.num_functions(), layout, iu, iv)) return nullptr;
  // u: K_u weighted by a1 and M_u by a2; v: M_v by b1 and K_v by b2.
  const auto& side = nitsche.sides;  // bottom, right, top, left
  const UnivariatePair pu = univariate_pair(space_u, geometry.a2, geometry.a1, side[3], side[1], nitsche.factor);
  const UnivariatePair pv = univariate_pair(space_v, geometry.b1, geometry.b2, side[0], side[2], nitsche.factor);
  Eigen::MatrixXd Uu, Uv;
  Eigen::VectorXd lu, lv;
  diagonalize(pu, iu, Uu, lu);
  // The same knots, free indices and weights in both directions (square grids on maps
  // symmetric in u and v, such as the unit square): one decomposition serves both.
  // (Weights equal up to rounding count as equal: a preconditioner needs no last bits.)
  auto same = [](const std::vector<double>& x, const std::vector<double>& y) {
    if (x.size() != y.size()) return false;
    for (size_t k = 0; k < x.size(); ++k)
      if (std::abs(x[k] - y[k]) > 1e-12 * std::max(std::abs(x[k]), std::abs(y[k]))) return false;
    return true;
  };
  if (space_u.degree() == space_v.degree() && space_u.knots() == space_v.knots() && iu == iv &&
      same(geometry.a1, geometry.b2) && same(geometry.a2, geometry.b1) && side[3] == side[0] && side[1] == side[2]) {
    Uv = Uu;
    lv = lu;
  } else {
    diagonalize(pv, iv, Uv, lv);
  }
  // D = diag(K) / diag(P): P_dd = (K_u)_ii (M_v)_jj + (M_u)_ii (K_v)_jj + shift (M_u)_ii (M_v)_jj.
  const Eigen::VectorXd ku = pu.stiffness.diagonal(), mu = pu.mass.diagonal();
  const Eigen::VectorXd kv = pv.stiffness.diagonal(), mv = pv.mass.diagonal();
  Eigen::VectorXd scale(layout.num_free());
  for (size_t b = 0; b < iv.size(); ++b)
    for (size_t a = 0; a < iu.size(); ++a) {
      const Eigen::Index d = static_cast<Eigen::Index>(a + iu.size() * b);
      const double p = ku[iu[a]] * mv[iv[b]] + mu[iu[a]] * kv[iv[b]] + geometry.shift * mu[iu[a]] * mv[iv[b]];
      scale[d] = diag[d] > 0 && p > 0 ? std::sqrt(p / diag[d]) : 1.0;
    }
  return std::make_unique<FastDiagonalization>(std::move(Uu), std::move(lu), std::move(Uv), std::move(lv),
                                               std::move(scale), geometry.shift);
}

}  // namespace knotwork
