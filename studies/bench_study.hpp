#pragma once
// The benchmark study: one configuration of `knotwork bench` (the unit square,
// u = sin(pi x) sin(pi y), degree p, n x n elements; or the unit cube, u = sin(pi x) sin(pi y)
// sin(pi z), n^3 hexahedra), timed phase by phase.
#include <cmath>
#include <string>

#include "solver/linear_solver.hpp"

namespace knotwork {

struct BenchResult {
  int degree = 0, elements = 0;
  long dofs = 0, free_dofs = 0, matrix_nonzeros = 0;
  double factor_nonzeros = 0, flops = 0;
  double setup = 0, assembly = 0, analysis = 0, factorization = 0, solve = 0, errors = 0, total = 0;
  double cholmod_peak_bytes = 0, l2 = 0;
  double floor_seconds = NAN;  // bare CHOLMOD, default settings: analyze + factorize + solve
  long peak_rss_kb = 0;
  // --solver iterative: CG with the space's own ([solver] preconditioner = "auto").
  int iterations = 0;
  double preconditioner = 0, cg = 0, relative_residual = 0;
  char assembly_name[32] = {};  // PoissonSolution::assembly
  char preconditioner_name[32] = {};  // the one used (what "auto" chose); a char array: the
                                      // result crosses a pipe from the configuration's process
};

// Solves the configuration with the direct solver (and, with `floor`, bare CHOLMOD on the same
// matrix) or, with solver "iterative", CG to backward error `tolerance` with `preconditioner`
// (as [solver] preconditioner) and K as `matrix` says (as [solver] matrix).
BenchResult bench_configuration(int p, int n, Ordering ordering, bool with_errors, bool floor, const std::string& solver,
                                double tolerance, const std::string& preconditioner = "auto",
                                const std::string& matrix = "auto", bool cube = false);

}  // namespace knotwork
