#include "solver/iterative_solver.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace knotwork {

namespace {

class JacobiPreconditioner final : public Preconditioner {
 public:
  explicit JacobiPreconditioner(Eigen::VectorXd inverse_diagonal) : inv_(std::move(inverse_diagonal)) {}
  void apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const override { z = inv_.cwiseProduct(r); }

 private:
  Eigen::VectorXd inv_;
};

}  // namespace

std::unique_ptr<Preconditioner> jacobi_preconditioner(const Eigen::SparseMatrix<double>& lower) {
  Eigen::VectorXd d = lower.diagonal();
  for (Eigen::Index i = 0; i < d.size(); ++i) d[i] = d[i] > 0 ? 1.0 / d[i] : 1.0;
  return std::make_unique<JacobiPreconditioner>(std::move(d));
}

namespace {

// A matrix of which the lower triangle is stored: its ||K||_inf (the largest absolute row sum)
// and most nonzeros in a row, each entry counting in its row and, off the diagonal, in its
// column's row.
class LowerTriangle final : public SymmetricOperator {
 public:
  explicit LowerTriangle(const Eigen::SparseMatrix<double>& lower) : lower_(lower) {
    const Eigen::Index n = lower.rows();
    Eigen::VectorXd row_sums = Eigen::VectorXd::Zero(n);
    Eigen::VectorXi row_count = Eigen::VectorXi::Zero(n);
    const int* outer = lower.outerIndexPtr();
    const int* inner = lower.innerIndexPtr();
    const double* value = lower.valuePtr();
    for (Eigen::Index j = 0; j < lower.outerSize(); ++j)
      for (int k = outer[j]; k < outer[j + 1]; ++k) {
        row_sums[inner[k]] += std::abs(value[k]);
        ++row_count[inner[k]];
        if (inner[k] != j) row_sums[j] += std::abs(value[k]), ++row_count[j];
      }
    norm_ = n > 0 ? row_sums.maxCoeff() : 0;
    most_ = n > 0 ? row_count.maxCoeff() : 0;
  }
  void apply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const override {
    y.noalias() = lower_.selfadjointView<Eigen::Lower>() * x;
  }
  double inf_norm() const override { return norm_; }
  int max_row_nonzeros() const override { return most_; }

 private:
  const Eigen::SparseMatrix<double>& lower_;
  double norm_ = 0;
  int most_ = 0;
};

}  // namespace

Eigen::VectorXd preconditioned_cg(const Eigen::SparseMatrix<double>& lower, const Eigen::VectorXd& b,
                                  const Preconditioner& preconditioner, double tolerance, int max_iterations,
                                  IterativeStats& stats, const Eigen::VectorXd* initial, double energy_tolerance) {
  return preconditioned_cg(LowerTriangle(lower), b, preconditioner, tolerance, max_iterations, stats, initial, energy_tolerance);
}

Eigen::VectorXd preconditioned_cg(const SymmetricOperator& K, const Eigen::VectorXd& b, const Preconditioner& preconditioner,
                                  double tolerance, int max_iterations, IterativeStats& stats, const Eigen::VectorXd* initial,
                                  double energy_tolerance) {
  const Eigen::Index n = b.size();
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n), r = b, z(n), p(n), q(n);
  const double b_norm = b.norm();
  stats = {};
  if (b_norm == 0) {
    stats.converged = true;
    return x;
  }
  if (initial && initial->size() > 0) {
    if (initial->size() != n) throw std::invalid_argument("CG: an initial guess of the wrong size");
    x = *initial;
    K.apply(x, q);
    r = b - q;
  }
  const double k_norm = K.inf_norm(), b_inf = b.lpNorm<Eigen::Infinity>();
  const double m_eps = (K.max_row_nonzeros() + 1) * std::numeric_limits<double>::epsilon();
  stats.attainable = m_eps / (1 - std::min(m_eps, 0.5));
  auto backward_error = [&](const Eigen::VectorXd& residual) {
    return residual.lpNorm<Eigen::Infinity>() / (k_norm * x.lpNorm<Eigen::Infinity>() + b_inf);
  };
  // The recurrence's residual drifts from b - K x in the last digits: when it says converged
  // and the true residual does not, CG restarts from x with the true one.
  // Stagnation (kStagnationFactor): no 10% improvement over a window that grows with the
  // iteration count, and only near the attainable accuracy.
  if (initial && initial->size() > 0 && backward_error(r) <= tolerance) {  // already solved
    stats.relative_residual = r.norm() / b_norm;
    stats.backward_error = backward_error(r);
    stats.converged = true;
    return x;
  }
  double best = INFINITY;
  int best_at = 0;
  bool stagnated = false, energy_small = false;
  // The algebraic error's energy (Hestenes-Stiefel; Strakos, Tichy 2002): an iteration lowers
  // ||x* - x||_K^2 by alpha r^T z exactly (in exact arithmetic), so the last kEnergyDelay
  // decreases sum to a lower bound of the error's energy kEnergyDelay iterations back, which
  // bounds the present iterate's once CG contracts (measured: docs/ADAPTIVITY.md).
  constexpr int kEnergyDelay = 2;
  double decrease[kEnergyDelay] = {INFINITY, INFINITY};
  const auto energy_reached = [&]() {
    stats.energy_estimate = std::sqrt(decrease[0] + decrease[1]);
    return energy_small = energy_tolerance > 0 && stats.energy_estimate <= energy_tolerance;
  };
  while (stats.iterations < max_iterations && !stagnated && !energy_small) {
    preconditioner.apply(r, z);
    p = z;
    double rz = r.dot(z);
    bool breakdown = false;
    while (stats.iterations < max_iterations && !energy_reached()) {
      K.apply(p, q);
      const double pq = p.dot(q);
      if (!(pq > 0)) {  // not positive definite along p, or a NaN
        breakdown = true;
        break;
      }
      const double alpha = rz / pq;
      decrease[stats.iterations % kEnergyDelay] = alpha * rz;
      x.noalias() += alpha * p;
      r.noalias() -= alpha * q;
      ++stats.iterations;
      const double omega = backward_error(r);
      if (omega <= tolerance) break;
      if (omega < 0.9 * best) best = omega, best_at = stats.iterations;
      const int window = std::max(30, stats.iterations / 2);
      if (stats.iterations - best_at >= window && best <= kStagnationFactor * stats.attainable) {
        stagnated = true;
        stats.stagnation_window = stats.iterations - best_at;
        break;
      }
      preconditioner.apply(r, z);
      const double rz_next = r.dot(z);
      p = z + (rz_next / rz) * p;
      rz = rz_next;
    }
    K.apply(x, q);
    r = b - q;
    stats.relative_residual = r.norm() / b_norm;
    stats.backward_error = backward_error(r);
    const bool accurate = stats.backward_error <= tolerance;
    stats.converged = accurate || energy_small;
    stats.stop = accurate       ? IterativeStats::Stop::kConverged
                 : energy_small ? IterativeStats::Stop::kEnergy
                 : breakdown    ? IterativeStats::Stop::kBreakdown
                 : stagnated    ? IterativeStats::Stop::kStagnated
                                : IterativeStats::Stop::kMaxIterations;
    if (stats.converged || breakdown) break;
  }
  return x;
}

std::string IterativeStats::stop_reason() const {
  char b[200];
  switch (stop) {
    case Stop::kConverged:
      return "converged";
    case Stop::kEnergy:
      return "converged: the algebraic error's energy estimate below its tolerance";
    case Stop::kStagnated:
      std::snprintf(b, sizeof b, "stagnated: no 10%% progress over the last %d iterations within %.0e of the attainable "
                                 "backward error %.1e", stagnation_window, kStagnationFactor, attainable);
      return b;
    case Stop::kMaxIterations:
      return "reached max_iterations";
    case Stop::kBreakdown:
      return "broke down (p^T K p <= 0: the matrix or the preconditioner is not positive definite)";
  }
  return "";
}

}  // namespace knotwork
