// The condition estimate against a matrix whose eigenvalues are known in closed form, and
// CG's stopping rules: each rule ends the iteration where it should and says so.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <vector>

#include "solver/condition_estimate.hpp"
#include "solver/iterative_solver.hpp"

using namespace knotwork;

namespace {

// Lower triangle of s_i s_j T, T = tridiag(-1, 2, -1) of size n: Jacobi scaling removes the
// s_i, leaving T / 2, whose eigenvalues are 1 - cos(k pi / (n + 1)), k = 1..n.
Eigen::SparseMatrix<double> scaled_laplacian(int n, bool scaled) {
  std::vector<Eigen::Triplet<double>> t;
  auto s = [&](int i) { return scaled ? std::pow(10.0, (i % 7) - 3) : 1.0; };  // 1e-3 .. 1e3
  for (int i = 0; i < n; ++i) {
    t.emplace_back(i, i, 2 * s(i) * s(i));
    if (i + 1 < n) t.emplace_back(i + 1, i, -s(i) * s(i + 1));
  }
  Eigen::SparseMatrix<double> A(n, n);
  A.setFromTriplets(t.begin(), t.end());
  return A;
}

}  // namespace

TEST_CASE("Jacobi-scaled condition estimate: the 1D Laplacian's eigenvalues, whatever the scaling", "[solver][condition]") {
  for (int n : {10, 300}) {  // the dense path (n <= 24) and Lanczos
    const double smallest = 1 - std::cos(M_PI / (n + 1)), largest = 1 + std::cos(M_PI / (n + 1));
    for (bool scaled : {false, true}) {
      INFO("n = " << n << ", rows scaled by 1e-3 .. 1e3: " << scaled);
      const SpectrumEstimate e = jacobi_scaled_spectrum(scaled_laplacian(n, scaled), true);
      REQUIRE(e.computed);
      // Lanczos converged to 1e-8 relative in each eigenvalue (Spectra's tolerance); 1e-6 here.
      CHECK(e.smallest == Approx(smallest).epsilon(1e-6));
      CHECK(e.largest == Approx(largest).epsilon(1e-6));
      CHECK(e.condition() == Approx(largest / smallest).epsilon(2e-6));
      REQUIRE(e.smallest_vector.size() == n);
    }
  }
  // Not positive definite: said, not estimated.
  Eigen::SparseMatrix<double> bad = scaled_laplacian(50, false);
  bad.coeffRef(10, 10) = -1;
  const SpectrumEstimate e = jacobi_scaled_spectrum(bad);
  CHECK_FALSE(e.computed);
  CHECK_FALSE(e.failure.empty());
}

TEST_CASE("CG's stopping rules: converged, max_iterations honoured, stagnation only at rounding level, breakdown", "[solver][cg]") {
  const int n = 400;
  const Eigen::SparseMatrix<double> A = scaled_laplacian(n, false);
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, 1.0, 2.0);
  const auto jacobi = jacobi_preconditioner(A);
  IterativeStats stats;

  // In exact arithmetic CG ends in n iterations; in floating point it takes more, with a
  // residual that is not monotone on the way.
  preconditioned_cg(A, b, *jacobi, 1e-15, 5 * n, stats);
  INFO("iterations " << stats.iterations << ", backward error " << stats.backward_error << ": " << stats.stop_reason());
  CHECK(stats.converged);
  CHECK(stats.stop == IterativeStats::Stop::kConverged);

  // The limit asked for is the limit used.
  preconditioned_cg(A, b, *jacobi, 1e-15, 7, stats);
  CHECK(stats.iterations == 7);
  CHECK(stats.stop == IterativeStats::Stop::kMaxIterations);
  CHECK(stats.stop_reason() == "reached max_iterations");

  // A tolerance below what rounding allows: stopped as stagnated, near the attainable level,
  // long before the limit, and the reason names the rule.
  preconditioned_cg(A, b, *jacobi, 1e-30, 50 * n, stats);
  CHECK(stats.stop == IterativeStats::Stop::kStagnated);
  CHECK(stats.backward_error <= kStagnationFactor * stats.attainable);
  CHECK(stats.iterations < 50 * n);
  CHECK(stats.stagnation_window >= 30);
  CHECK(stats.stop_reason().find("stagnated") == 0);
  // gamma_m for at most 3 nonzeros a row (and the diagonal counted once more: m = 4).
  CHECK(stats.attainable == Approx(4 * std::numeric_limits<double>::epsilon()).epsilon(1e-6));

  // Not positive definite along the first direction.
  Eigen::SparseMatrix<double> indefinite = A;
  for (int i = 0; i < n; ++i) indefinite.coeffRef(i, i) = -2;
  const auto identity = jacobi_preconditioner(A);
  preconditioned_cg(indefinite, b, *identity, 1e-15, 100, stats);
  CHECK(stats.stop == IterativeStats::Stop::kBreakdown);
  CHECK_FALSE(stats.converged);
}
