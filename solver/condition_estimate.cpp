#include "solver/condition_estimate.hpp"

#include <Eigen/Eigenvalues>
#include <Spectra/SymEigsSolver.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "solver/iterative_solver.hpp"
#include "solver/linear_solver.hpp"

namespace knotwork {

namespace {

// y = S x for the scaled matrix S (lower triangle stored).
struct ScaledProduct {
  using Scalar = double;
  const Eigen::SparseMatrix<double>* lower;
  Eigen::Index rows() const { return lower->rows(); }
  Eigen::Index cols() const { return lower->cols(); }
  void perform_op(const double* x, double* y) const {
    Eigen::Map<Eigen::VectorXd>(y, rows()).noalias() =
        lower->selfadjointView<Eigen::Lower>() * Eigen::Map<const Eigen::VectorXd>(x, rows());
  }
};

// y = S^{-1} x through one Cholesky factorization.
struct ScaledInverse {
  using Scalar = double;
  SparseCholesky* cholesky;
  Eigen::Index n;
  Eigen::Index rows() const { return n; }
  Eigen::Index cols() const { return n; }
  void perform_op(const double* x, double* y) const {
    Eigen::Map<Eigen::VectorXd>(y, n) = cholesky->solve(Eigen::Map<const Eigen::VectorXd>(x, n));
  }
};

template <class Op>
bool largest_eigenpair(Op& op, double& value, Eigen::VectorXd* vector) {
  const Eigen::Index n = op.rows();
  Spectra::SymEigsSolver<Op> eigs(op, 1, std::min<Eigen::Index>(n, 24));
  eigs.init();
  eigs.compute(Spectra::SortRule::LargestAlge, 3000, 1e-8);
  if (eigs.info() != Spectra::CompInfo::Successful) return false;
  value = eigs.eigenvalues()(0);
  if (vector) *vector = eigs.eigenvectors().col(0);
  return true;
}

}  // namespace

SpectrumEstimate jacobi_scaled_spectrum(const Eigen::SparseMatrix<double>& lower, bool want_vector) {
  SpectrumEstimate s;
  const Eigen::Index n = lower.rows();
  if (n == 0) {
    s.failure = "no unknowns";
    return s;
  }
  Eigen::VectorXd d = lower.diagonal();
  if (!(d.minCoeff() > 0)) {
    s.failure = "a diagonal entry is not positive";
    return s;
  }
  const Eigen::VectorXd scale = d.cwiseSqrt().cwiseInverse();
  Eigen::SparseMatrix<double> S = lower;
  for (Eigen::Index j = 0; j < S.outerSize(); ++j)
    for (Eigen::SparseMatrix<double>::InnerIterator it(S, j); it; ++it) it.valueRef() *= scale(it.row()) * scale(j);
  if (n <= 24) {
    const Eigen::MatrixXd dense = Eigen::MatrixXd(S).selfadjointView<Eigen::Lower>();
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(dense);
    s.smallest = eig.eigenvalues()(0);
    s.largest = eig.eigenvalues()(n - 1);
    if (want_vector) s.smallest_vector = scale.cwiseProduct(eig.eigenvectors().col(0));
    s.computed = s.smallest > 0;
    if (!s.computed) s.failure = "the matrix is not positive definite";
    return s;
  }
  ScaledProduct product{&S};
  if (!largest_eigenpair(product, s.largest, nullptr)) {
    s.failure = "Lanczos did not converge to the largest eigenvalue";
    return s;
  }
  try {
    SparseCholesky cholesky;
    cholesky.factorize(S);
    ScaledInverse inverse{&cholesky, n};
    double inverse_largest = 0;
    Eigen::VectorXd v;
    if (!largest_eigenpair(inverse, inverse_largest, want_vector ? &v : nullptr) || !(inverse_largest > 0)) {
      s.failure = "Lanczos did not converge to the smallest eigenvalue";
      return s;
    }
    s.smallest = 1 / inverse_largest;
    if (want_vector) s.smallest_vector = scale.cwiseProduct(v);
  } catch (const std::runtime_error& e) {
    s.failure = std::string("the Cholesky factorization of the scaled matrix failed: ") + e.what();
    return s;
  }
  s.computed = true;
  return s;
}

}  // namespace knotwork
