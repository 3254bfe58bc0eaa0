#pragma once
// What every iterative solve must show against the direct one on the same system: CG stopped at
// its backward-error tolerance, and the algebraic error invisible in the discretization error
// (the L2 and H1 errors agree with CHOLMOD's to 1e-4 relative, far below the gap between levels).
#include <catch2/catch.hpp>

#include "solver/poisson_solver.hpp"

inline void require_direct_errors(const knotwork::PoissonSolution& cg, const knotwork::PoissonSolution& direct) {
  REQUIRE(cg.iterative.converged);
  REQUIRE(cg.errors->l2 == Approx(direct.errors->l2).epsilon(1e-4));
  REQUIRE(cg.errors->h1_semi == Approx(direct.errors->h1_semi).epsilon(1e-4));
}
