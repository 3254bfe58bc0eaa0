#pragma once
// Tolerances for checks of rounding: a solve that should reproduce a function of the space (a
// patch test, a polynomial in the space) leaves an error made of rounding alone, and how much
// depends on the conditioning of the system and on the CPU's BLAS kernels (OpenBLAS's Prescott
// kernel rounds differently from Haswell's). So the bound is stated from the solve's own
// condition estimates (solver/condition_estimate.hpp), not as a fixed number:
//
//   the solve is backward stable on the Jacobi-scaled system S (K = D^1/2 S D^1/2), with a
//   backward error of at most c eps ||S||, c = 1000 covering the longest sums (quadrature over a
//   cell, the cells of a function's support, a Cholesky row: a few hundred terms). In the
//   energy norm of K that gives ||u - u_h||_K <= c eps kappa(S) ||u||_K, and the energy norm is
//   the H1 seminorm here (with Nitsche's terms an equivalent norm):
//     |u - u_h|_1 <= c eps kappa(K) |u|_1.
//   In L2 the scaled coefficients' error, c eps kappa(K) relative, passes through the mass
//   matrix scaled by K's diagonal; on these quasi-uniform meshes diag(M)/diag(K) varies little
//   (about h^2 everywhere), so that matrix is conditioned about as the Jacobi-scaled M:
//     ||u - u_h||_L2 <= c eps kappa(K) sqrt(kappa(M)) ||u||_L2.
// Measured: the errors sit 1e3 to 1e6 below these bounds (c eps kappa(K) |u|_1 from 2e-12 to
// 8e-10 on the tests that use it; errors 1e-15 to 7e-13).
#include <cmath>
#include <limits>

#include "solver/poisson_solver.hpp"

namespace rounding_test {

struct Reproduction {
  knotwork::ErrorNorms errors;  // of u_h against u
  knotwork::ErrorNorms size;    // ||u||: the errors of the zero function
  double kappa_stiffness = 0, kappa_mass = 0;
  double factor = 0;            // c eps kappa(K): the H1 bound relative to |u|_1
  Eigen::VectorXd coefficients; // u_h
  double refinement_correction = 0;  // CHOLMOD's (CholeskyStats): at most c eps kappa(K), factor
  double l2_bound() const { return factor * std::sqrt(kappa_mass) * size.l2; }
  double h1_bound() const { return factor * size.h1_semi; }
  bool reproduced() const { return errors.l2 <= l2_bound() && errors.h1_semi <= h1_bound(); }
  double correction_bound() const { return factor; }
};

inline Reproduction solve_reproducing(const knotwork::BezierMesh& mesh, const knotwork::GeometryMap& geometry,
                                      const knotwork::PoissonProblem& problem,
                                      knotwork::PoissonSolveOptions options = {}) {
  options.estimate_condition = true;
  const knotwork::PoissonSolution s = knotwork::solve_poisson(mesh, geometry, problem, options);
  Reproduction r;
  r.errors = *s.errors;
  r.coefficients = s.coefficients;
  r.size = knotwork::error_norms(mesh, geometry, Eigen::VectorXd::Zero(mesh.num_functions()), *problem.exact,
                                 options.quadrature, nullptr, s.exact_mean);
  r.refinement_correction = s.cholesky.refinement_correction;
  r.kappa_stiffness = s.stiffness_spectrum.condition();
  r.kappa_mass = s.mass_spectrum.condition();
  // No estimate (a tiny system, done densely, always has one): no bound, the check fails.
  r.factor = r.kappa_stiffness > 0 && r.kappa_mass > 0
                 ? 1e3 * std::numeric_limits<double>::epsilon() * r.kappa_stiffness
                 : 0;
  return r;
}

}  // namespace rounding_test

// Catch2: the reproduction within its bound, with the numbers on failure.
#define REQUIRE_REPRODUCED(r)                                                                          \
  do {                                                                                                 \
    const rounding_test::Reproduction& reproduction_ = (r);                                           \
    INFO("L2 " << reproduction_.errors.l2 << " (bound " << reproduction_.l2_bound() << "), H1 "        \
               << reproduction_.errors.h1_semi << " (bound " << reproduction_.h1_bound()               \
               << "), kappa(K) " << reproduction_.kappa_stiffness << ", kappa(M) "                     \
               << reproduction_.kappa_mass);                                                           \
    REQUIRE(reproduction_.reproduced());                                                               \
  } while (false)
