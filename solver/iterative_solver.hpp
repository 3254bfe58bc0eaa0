#pragma once
// Preconditioned conjugate gradients on the free-dof system, for when a factorization costs
// too much (O(N^1.5) time and O(N log N) memory in 2D). The preconditioner comes from the
// space's family when it knows a structure, or is algebraic (Jacobi); docs/SOLVERS.md says
// which is used when, and why.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <string>

namespace knotwork {

// z = P^{-1} r on the free dofs.
class Preconditioner {
 public:
  virtual ~Preconditioner() = default;
  virtual void apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const = 0;
};

// The diagonal of the matrix (lower triangle stored): needs no structure, serves every family.
std::unique_ptr<Preconditioner> jacobi_preconditioner(const Eigen::SparseMatrix<double>& lower);

struct IterativeStats {
  int iterations = 0;
  double relative_residual = 0;  // ||b - K x||_2 / ||b||_2 at the end
  // The normwise backward error ||b - K x||_inf / (||K||_inf ||x||_inf + ||b||_inf): the
  // relative size of the smallest change of K and b that x solves exactly. It is what the
  // tolerance bounds: unlike the relative residual it can reach rounding level (about
  // 1e-16) whatever the condition number, and a backward-stable direct solver reaches the
  // same, so at a small tolerance the errors are the direct solve's (docs/SOLVERS.md).
  double backward_error = 0;
  // The algebraic error's energy norm as CG estimates it at the end (energy_tolerance).
  double energy_estimate = 0;
  bool converged = false;
  // Why the iteration ended: converged, stagnated at the attainable accuracy, the iteration
  // limit, or a breakdown (p^T K p <= 0: K or the preconditioner is not positive definite).
  // kEnergy: converged by energy_tolerance, before the backward error reached `tolerance`.
  enum class Stop { kConverged, kEnergy, kStagnated, kMaxIterations, kBreakdown } stop = Stop::kConverged;
  // The backward error that rounding alone leaves in a computed residual: gamma_m = m eps /
  // (1 - m eps), m the most nonzeros in a row of K. Stagnation is declared only within
  // kStagnationFactor of it.
  double attainable = 0;
  int stagnation_window = 0;  // the iterations without progress that ended it (kStagnated)
  std::string stop_reason() const;  // one phrase: "converged", "reached max_iterations", ...
};

// CG is stopped as stagnated only when its backward error is within this factor of the
// attainable accuracy (IterativeStats::attainable) and has not improved by 10% over the last
// max(30, iterations / 2) iterations. Above that level a stalled residual says nothing: CG's
// residual is not monotone, and the energy error keeps falling through long plateaus on
// ill-conditioned systems, so the iteration goes on to max_iterations.
constexpr double kStagnationFactor = 1e3;

// K for CG: its product, ||K||_inf (or a lower bound of it: the backward errors CG then
// measures are upper bounds of the true ones, so it never stops early) and the most nonzeros
// in a row (the attainable accuracy).
class SymmetricOperator {
 public:
  virtual ~SymmetricOperator() = default;
  virtual void apply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const = 0;
  virtual double inf_norm() const = 0;
  virtual int max_row_nonzeros() const = 0;
};

// CG on K (symmetric positive definite) from x = `initial` (null or empty: 0) until the
// backward error of x is at most `tolerance` (measured with the true residual b - K x) or
// max_iterations. With energy_tolerance > 0 it also stops (converged) once its estimate of the
// algebraic error's energy norm ||x* - x||_K is at most energy_tolerance: the square root of
// the last two iterations' decreases of that energy (alpha r^T z each), what an adaptive loop
// compares with its error estimator.
Eigen::VectorXd preconditioned_cg(const SymmetricOperator& K, const Eigen::VectorXd& b, const Preconditioner& preconditioner,
                                  double tolerance, int max_iterations, IterativeStats& stats,
                                  const Eigen::VectorXd* initial = nullptr, double energy_tolerance = 0);
// The same on a matrix of which the lower triangle is stored.
Eigen::VectorXd preconditioned_cg(const Eigen::SparseMatrix<double>& lower, const Eigen::VectorXd& b,
                                  const Preconditioner& preconditioner, double tolerance, int max_iterations,
                                  IterativeStats& stats, const Eigen::VectorXd* initial = nullptr,
                                  double energy_tolerance = 0);

}  // namespace knotwork
